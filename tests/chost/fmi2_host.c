/* A minimal native FMI 2.0 co-simulation host (no Python in this program).
 *
 * Usage: fmi2_host SHARED_LIBRARY GUID RESOURCE_URI STEP_SIZE N_STEPS ARG [ARG ...]
 *
 * Each ARG is a value reference: "VR" reads a Real output at the end, "VR=VALUE" sets a Real
 * input to VALUE before every step, "VR=t" to the end time of the step, "VR=h" to STEP_SIZE,
 * and "VR=s:TEXT" sets a String parameter to TEXT before initialization.
 * Loads the FMU's binary with dlopen, instantiates it, runs setupExperiment (start 0), sets
 * the String parameters, enter/exitInitializationMode, N_STEPS times fmi2SetReal (the inputs) and fmi2DoStep from
 * k * STEP_SIZE, then reads the outputs in one fmi2GetReal call and prints them, one "%.17g"
 * per line, calls fmi2Terminate and fmi2FreeInstance and returns from main without unloading
 * the library (as most simulators end).  Exit status: 0 on success, 1 on a usage or load
 * error, 2 when an FMI call returns fmi2Error or worse (or a doStep anything but fmi2OK).
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi2_host_util.h"

#define CHECK(call, what)                                                          \
    do {                                                                           \
        fmi2Status s_ = (call);                                                    \
        if (s_ >= fmi2Error) {                                                     \
            fprintf(stderr, "fmi2_host: %s returned status %d\n", what, (int)s_); \
            return 2;                                                              \
        }                                                                          \
    } while (0)

int main(int argc, char **argv)
{
    if (argc < 7) {
        fprintf(stderr, "usage: %s SHARED_LIBRARY GUID RESOURCE_URI STEP_SIZE N_STEPS ARG...\n",
                argv[0]);
        return 1;
    }
    const char *guid = argv[2], *resources = argv[3];
    double h = atof(argv[4]);
    int n_steps = atoi(argv[5]), n_args = argc - 6, n_out = 0, n_in = 0;
    fmi2ValueReference *out_vr = calloc((size_t)n_args, sizeof *out_vr);
    fmi2ValueReference *in_vr = calloc((size_t)n_args, sizeof *in_vr);
    fmi2Real *values = calloc((size_t)n_args, sizeof *values);
    fmi2Real *in_values = calloc((size_t)n_args, sizeof *in_values);
    char *in_kind = calloc((size_t)n_args, 1); /* 'v' constant, 't' step end time, 'h' step */
    fmi2ValueReference *str_vr = calloc((size_t)n_args, sizeof *str_vr);
    fmi2String *str_values = calloc((size_t)n_args, sizeof *str_values);
    int n_str = 0;
    for (int i = 0; i < n_args; ++i) {
        char *rest;
        fmi2ValueReference r = (fmi2ValueReference)strtoul(argv[6 + i], &rest, 10);
        if (*rest == '\0') {
            out_vr[n_out++] = r;
        } else if (strncmp(rest, "=s:", 3) == 0) {
            str_vr[n_str] = r;
            str_values[n_str++] = rest + 3;
        } else if (*rest == '=') {
            in_vr[n_in] = r;
            in_kind[n_in] = strcmp(rest + 1, "t") == 0 ? 't' : strcmp(rest + 1, "h") == 0 ? 'h' : 'v';
            in_values[n_in++] = atof(rest + 1);
        } else {
            fprintf(stderr, "fmi2_host: bad argument %s\n", argv[6 + i]);
            return 1;
        }
    }

    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        fprintf(stderr, "fmi2_host: cannot load %s: %s\n", argv[1], dlerror());
        return 1;
    }
    fmi2InstantiateTYPE *instantiate = load(lib, "fmi2Instantiate");
    fmi2SetupExperimentTYPE *setup = load(lib, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter = load(lib, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *exit_init = load(lib, "fmi2ExitInitializationMode");
    fmi2DoStepTYPE *do_step = load(lib, "fmi2DoStep");
    fmi2GetRealTYPE *get_real = load(lib, "fmi2GetReal");
    fmi2SetRealTYPE *set_real = load(lib, "fmi2SetReal");
    fmi2SetStringTYPE *set_string = load(lib, "fmi2SetString");
    fmi2TerminateTYPE *terminate = load(lib, "fmi2Terminate");
    fmi2FreeInstanceTYPE *free_instance = load(lib, "fmi2FreeInstance");

    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = instantiate("host", fmi2CoSimulation, guid, resources, &callbacks,
                                  fmi2False, fmi2False);
    if (c == NULL) {
        fprintf(stderr, "fmi2_host: fmi2Instantiate failed\n");
        return 2;
    }
    CHECK(setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), "fmi2SetupExperiment");
    if (n_str > 0) CHECK(set_string(c, str_vr, (size_t)n_str, str_values), "fmi2SetString");
    CHECK(enter(c), "fmi2EnterInitializationMode");
    CHECK(exit_init(c), "fmi2ExitInitializationMode");
    for (int k = 0; k < n_steps; ++k) {
        for (int i = 0; i < n_in; ++i) {
            if (in_kind[i] == 't') in_values[i] = (k + 1) * h;
            if (in_kind[i] == 'h') in_values[i] = h;
        }
        if (n_in > 0) CHECK(set_real(c, in_vr, (size_t)n_in, in_values), "fmi2SetReal");
        fmi2Status s = do_step(c, k * h, h, fmi2True);
        if (s != fmi2OK) {
            fprintf(stderr, "fmi2_host: fmi2DoStep at t=%g returned status %d\n", k * h, (int)s);
            return 2;
        }
    }
    CHECK(get_real(c, out_vr, (size_t)n_out, values), "fmi2GetReal");
    for (int i = 0; i < n_out; ++i) printf("%.17g\n", values[i]);
    fflush(stdout);
    CHECK(terminate(c), "fmi2Terminate");
    free_instance(c);
    free(out_vr);
    free(in_vr);
    free(values);
    free(in_values);
    free(in_kind);
    free(str_vr);
    free(str_values);
    return 0;
}
