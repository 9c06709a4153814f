/* What the native test hosts share: the FMI logger (each message on one line of stderr) and
 * a dlsym that ends the program (status 1) when the FMU's binary lacks a function. */
#ifndef FMI2_HOST_UTIL_H
#define FMI2_HOST_UTIL_H

#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    va_list args;
    (void)env;
    fprintf(stderr, "[%s] status %d %s: ", instance ? instance : "?", (int)status,
            category ? category : "");
    va_start(args, message);
    vfprintf(stderr, message, args);
    va_end(args);
    fputc('\n', stderr);
}

static void *load(void *lib, const char *name)
{
    void *f = dlsym(lib, name);
    if (f == NULL) {
        fprintf(stderr, "fmi2 host: symbol %s not found: %s\n", name, dlerror());
        exit(1);
    }
    return f;
}

#endif
