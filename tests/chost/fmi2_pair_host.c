/* A native FMI 2.0 co-simulation host that runs several FMUs side by side in one process.
 *
 * Usage: fmi2_pair_host MODE CYCLES LIB GUID RESOURCE_URI STEP [LIB GUID RESOURCE_URI STEP ...]
 *
 * Loads each FMU's binary with dlopen (RTLD_NOW | RTLD_LOCAL), in the order given, then CYCLES
 * times: instantiates every FMU, runs setupExperiment (start 0), enter/exitInitializationMode,
 * three fmi2DoStep of STEP, fmi2Terminate and fmi2FreeInstance.  It then instantiates and
 * steps every FMU once more and, with MODE "free", frees those instances before returning
 * from main; with MODE "keep" it returns with them alive (as a simulator that ends without
 * cleaning up does).  No library is unloaded.  Exit status: 0 on success, 1 on a usage or
 * load error, 2 when an FMI call returns fmi2Error or worse.
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi2_host_util.h"

typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2DoStepTYPE *do_step;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_instance;
    const char *guid, *resources;
    double h;
} Fmu;

static fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

/* Instantiates and steps one FMU; NULL (after a message) when a call fails. */
static fmi2Component start(const Fmu *f, const char *name)
{
    fmi2Component c = f->instantiate(name, fmi2CoSimulation, f->guid, f->resources, &callbacks,
                                     fmi2False, fmi2False);
    if (c == NULL) {
        fprintf(stderr, "fmi2_pair_host: %s: fmi2Instantiate failed\n", name);
        return NULL;
    }
    if (f->setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) >= fmi2Error ||
        f->enter(c) >= fmi2Error || f->exit_init(c) >= fmi2Error) {
        fprintf(stderr, "fmi2_pair_host: %s: initialization failed\n", name);
        return NULL;
    }
    for (int k = 0; k < 3; ++k) {
        if (f->do_step(c, k * f->h, f->h, fmi2True) >= fmi2Error) {
            fprintf(stderr, "fmi2_pair_host: %s: fmi2DoStep failed\n", name);
            return NULL;
        }
    }
    return c;
}

int main(int argc, char **argv)
{
    if (argc < 7 || (argc - 3) % 4 != 0 ||
        (strcmp(argv[1], "free") != 0 && strcmp(argv[1], "keep") != 0)) {
        fprintf(stderr, "usage: %s free|keep CYCLES LIB GUID RESOURCE_URI STEP ...\n", argv[0]);
        return 1;
    }
    int keep = strcmp(argv[1], "keep") == 0, cycles = atoi(argv[2]), n = (argc - 3) / 4;
    Fmu *fmus = calloc((size_t)n, sizeof *fmus);
    fmi2Component *alive = calloc((size_t)n, sizeof *alive);
    char name[32];
    for (int i = 0; i < n; ++i) {
        char **a = argv + 3 + 4 * i;
        void *lib = dlopen(a[0], RTLD_NOW | RTLD_LOCAL);
        if (lib == NULL) {
            fprintf(stderr, "fmi2_pair_host: cannot load %s: %s\n", a[0], dlerror());
            return 1;
        }
        fmus[i] = (Fmu){load(lib, "fmi2Instantiate"), load(lib, "fmi2SetupExperiment"),
                        load(lib, "fmi2EnterInitializationMode"),
                        load(lib, "fmi2ExitInitializationMode"), load(lib, "fmi2DoStep"),
                        load(lib, "fmi2Terminate"), load(lib, "fmi2FreeInstance"),
                        a[1], a[2], atof(a[3])};
    }
    for (int cycle = 0; cycle <= cycles; ++cycle) {
        for (int i = 0; i < n; ++i) {
            snprintf(name, sizeof name, "fmu%d_%d", i, cycle);
            if ((alive[i] = start(&fmus[i], name)) == NULL) return 2;
        }
        if (cycle == cycles && keep) break;
        for (int i = 0; i < n; ++i) {
            if (fmus[i].terminate(alive[i]) >= fmi2Error) return 2;
            fmus[i].free_instance(alive[i]);
        }
    }
    printf("ok\n");
    fflush(stdout);
    free(fmus);
    free(alive);
    return 0;
}
