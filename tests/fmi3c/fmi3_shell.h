/* The FMI 3.0 co-simulation interface around one model, written for navfmu's tests after the
 * FMI 3.0 standard (its header fmi3Functions.h, as shipped with fmpy).  A model file defines
 * `struct Model` and the hooks below, then includes this file, which defines every fmi3*
 * function: the co-simulation ones over the hooks, the rest (model exchange, scheduled
 * execution, clocks, the types the tests' models do not have) as refusals returning fmi3Error
 * with a log message.
 *
 * Hooks (static; declared by the model before it includes this file, defined anywhere in it):
 *   void model_reset(struct Model *m);                     start values
 *   int  model_get(const struct Model *m, fmi3ValueReference vr, int kind, void *value);
 *   int  model_set(struct Model *m, fmi3ValueReference vr, int kind, const void *value,
 *                  int initializing);                      0 done, -1 no such variable of kind
 *   int  model_step(struct Model *m, double t, double h, bool *terminate, char *message,
 *                   size_t size);                          0 done, -1 refused (message says why)
 * with kind one of the K_* values below; `initializing` is 1 before initialization mode is
 * left (parameters may be set), 0 after (inputs only). */
#ifndef FMI3_SHELL_H
#define FMI3_SHELL_H

#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

enum { MODE_INSTANTIATED, MODE_INITIALIZATION, MODE_STEP, MODE_TERMINATED };

typedef struct {
    struct Model model;
    fmi3LogMessageCallback log;
    fmi3InstanceEnvironment environment;
    bool logging;
    int mode;
    double time;
} Instance;

static void say(Instance *inst, fmi3Status status, const char *category, const char *format, ...)
{
    char text[512];
    va_list args;
    if (!inst->log || (!inst->logging && status == fmi3OK)) return;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    inst->log(inst->environment, status, category, text);
}

static fmi3Status refuse(fmi3Instance instance, const char *function)
{
    say((Instance *)instance, fmi3Error, "logStatusError", "%s is not supported by this FMU",
        function);
    return fmi3Error;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    (void)nCategories; (void)categories;
    ((Instance *)instance)->logging = loggingOn;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    Instance *inst;
    (void)instanceName; (void)resourcePath; (void)visible; (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables; (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    if (strcmp(instantiationToken, MODEL_TOKEN) != 0) {
        if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                                   "wrong instantiation token");
        return NULL;
    }
    if (eventModeUsed) {
        if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                                   "this FMU has no event mode");
        return NULL;
    }
    inst = calloc(1, sizeof *inst);
    if (!inst) return NULL;
    inst->log = logMessage;
    inst->environment = instanceEnvironment;
    inst->logging = loggingOn;
    inst->mode = MODE_INSTANTIATED;
    model_reset(&inst->model);
    return inst;
}

fmi3Instance fmi3InstantiateModelExchange(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage)
{
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible;
    (void)loggingOn;
    if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                               "no model exchange");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible;
    (void)loggingOn; (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                               "no scheduled execution");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    Instance *inst = instance;
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    if (inst->mode != MODE_INSTANTIATED) return refuse(instance, "fmi3EnterInitializationMode now");
    inst->time = startTime;
    inst->mode = MODE_INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    Instance *inst = instance;
    if (inst->mode != MODE_INITIALIZATION)
        return refuse(instance, "fmi3ExitInitializationMode now");
    inst->mode = MODE_STEP;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    ((Instance *)instance)->mode = MODE_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    Instance *inst = instance;
    inst->mode = MODE_INSTANTIATED;
    model_reset(&inst->model);
    return fmi3OK;
}

/* getters and setters of the kinds the models have */
#define K_F64 0
#define K_I32 1
#define K_I64 2
#define K_BOOL 3
#define K_STR 4

static fmi3Status get_values(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                             void *values, size_t nValues, int kind, size_t size,
                             const char *function)
{
    Instance *inst = instance;
    size_t i;
    if (nvr != nValues) return refuse(instance, "an array variable");
    for (i = 0; i < nvr; i++) {
        if (model_get(&inst->model, vr[i], kind, (char *)values + i * size) != 0) {
            say(inst, fmi3Error, "logStatusError", "%s: no variable of this type with value "
                "reference %u", function, (unsigned)vr[i]);
            return fmi3Error;
        }
    }
    return fmi3OK;
}

static fmi3Status set_values(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                             const void *values, size_t nValues, int kind, size_t size,
                             const char *function)
{
    Instance *inst = instance;
    size_t i;
    int initializing = inst->mode == MODE_INSTANTIATED || inst->mode == MODE_INITIALIZATION;
    if (nvr != nValues) return refuse(instance, "an array variable");
    for (i = 0; i < nvr; i++) {
        if (model_set(&inst->model, vr[i], kind, (const char *)values + i * size,
                      initializing) != 0) {
            say(inst, fmi3Error, "logStatusError", "%s: value reference %u cannot be set now",
                function, (unsigned)vr[i]);
            return fmi3Error;
        }
    }
    return fmi3OK;
}

#define KNOWN_ACCESSORS(T, KIND)                                                               \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,    \
                          fmi3##T values[], size_t nValues)                                    \
    { return get_values(instance, vr, nvr, values, nValues, KIND, sizeof *values, "fmi3Get" #T); } \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,    \
                          const fmi3##T values[], size_t nValues)                              \
    { return set_values(instance, vr, nvr, values, nValues, KIND, sizeof *values, "fmi3Set" #T); }

KNOWN_ACCESSORS(Float64, K_F64)
KNOWN_ACCESSORS(Int32, K_I32)
KNOWN_ACCESSORS(Int64, K_I64)
KNOWN_ACCESSORS(Boolean, K_BOOL)

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         fmi3String values[], size_t nValues)
{
    return get_values(instance, vr, nvr, values, nValues, K_STR, sizeof *values, "fmi3GetString");
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3String values[], size_t nValues)
{
    return set_values(instance, vr, nvr, values, nValues, K_STR, sizeof *values, "fmi3SetString");
}

#define REFUSED_ACCESSORS(T)                                                                   \
    fmi3Status fmi3Get##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,    \
                          fmi3##T values[], size_t nValues)                                    \
    { (void)vr; (void)nvr; (void)values; (void)nValues; return refuse(instance, "fmi3Get" #T); } \
    fmi3Status fmi3Set##T(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,    \
                          const fmi3##T values[], size_t nValues)                              \
    { (void)vr; (void)nvr; (void)values; (void)nValues; return refuse(instance, "fmi3Set" #T); }

REFUSED_ACCESSORS(Float32)
REFUSED_ACCESSORS(Int8)
REFUSED_ACCESSORS(UInt8)
REFUSED_ACCESSORS(Int16)
REFUSED_ACCESSORS(UInt16)
REFUSED_ACCESSORS(UInt32)
REFUSED_ACCESSORS(UInt64)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    (void)vr; (void)nvr; (void)valueSizes; (void)values; (void)nValues;
    return refuse(instance, "fmi3GetBinary");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    (void)vr; (void)nvr; (void)valueSizes; (void)values; (void)nValues;
    return refuse(instance, "fmi3SetBinary");
}

/* refused functions of the shapes (instance, vr[], nvr, values[]) and
 * (instance, vr[], nvr, first[], second[]) */
#define REFUSED_VALUES(NAME, T)                                                                \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,          \
                    T values[])                                                                \
    { (void)vr; (void)nvr; (void)values; return refuse(instance, #NAME); }

#define REFUSED_PAIRS(NAME, T)                                                                 \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,          \
                    T first[], T second[])                                                     \
    { (void)vr; (void)nvr; (void)first; (void)second; return refuse(instance, #NAME); }

REFUSED_VALUES(fmi3GetClock, fmi3Clock)
REFUSED_VALUES(fmi3SetClock, const fmi3Clock)
REFUSED_VALUES(fmi3GetShiftDecimal, fmi3Float64)
REFUSED_VALUES(fmi3SetIntervalDecimal, const fmi3Float64)
REFUSED_VALUES(fmi3SetShiftDecimal, const fmi3Float64)
REFUSED_PAIRS(fmi3GetShiftFraction, fmi3UInt64)
REFUSED_PAIRS(fmi3SetIntervalFraction, const fmi3UInt64)
REFUSED_PAIRS(fmi3SetShiftFraction, const fmi3UInt64)

/* FMU state: a copy of the model */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state)
{
    Instance *inst = instance;
    Instance *copy = *state ? *state : malloc(sizeof *copy);
    if (!copy) return refuse(instance, "fmi3GetFMUState without memory");
    *copy = *inst;
    *state = copy;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state)
{
    Instance *inst = instance;
    const Instance *saved = state;
    inst->model = saved->model;
    inst->mode = saved->mode;
    inst->time = saved->time;
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state)
{
    (void)instance;
    free(*state);
    *state = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState state, size_t *size)
{
    (void)state; (void)size;
    return refuse(instance, "fmi3SerializedFMUStateSize");
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState state,
                                 fmi3Byte serializedState[], size_t size)
{
    (void)state; (void)serializedState; (void)size;
    return refuse(instance, "fmi3SerializeFMUState");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *state)
{
    (void)serializedState; (void)size; (void)state;
    return refuse(instance, "fmi3DeserializeFMUState");
}

/* stepping */
fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    return refuse(instance, "fmi3EnterStepMode (no event mode)");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    Instance *inst = instance;
    char message[256] = "";
    bool terminate = false;
    (void)noSetFMUStatePriorToCurrentPoint;
    *eventHandlingNeeded = false;
    *earlyReturn = false;
    *terminateSimulation = false;
    *lastSuccessfulTime = currentCommunicationPoint;
    if (inst->mode != MODE_STEP) return refuse(instance, "fmi3DoStep outside step mode");
    if (fabs(currentCommunicationPoint - inst->time) > 1e-9 * (1.0 + fabs(inst->time))) {
        say(inst, fmi3Error, "logStatusError", "fmi3DoStep from t = %g s: the FMU is at t = %g s",
            currentCommunicationPoint, inst->time);
        return fmi3Error;
    }
    if (model_step(&inst->model, currentCommunicationPoint, communicationStepSize, &terminate,
                   message, sizeof message) != 0) {
        say(inst, fmi3Error, "logStatusError", "%s", message);
        return fmi3Error;
    }
    inst->time = currentCommunicationPoint + communicationStepSize;
    *lastSuccessfulTime = inst->time;
    if (terminate) {
        say(inst, fmi3OK, "logEvents", "%s", message);
        *terminateSimulation = true;
    }
    return fmi3OK;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues)
{
    (void)vr; (void)nvr; (void)orders; (void)values; (void)nValues;
    return refuse(instance, "fmi3GetOutputDerivatives");
}

/* everything else: refused */
fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    return refuse(instance, "fmi3EnterEventMode");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                               size_t *n)
{
    (void)vr; (void)n;
    return refuse(instance, "fmi3GetNumberOfVariableDependencies");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t n)
{
    (void)dependent; (void)elementIndicesOfDependent; (void)independents;
    (void)elementIndicesOfIndependents; (void)dependencyKinds; (void)n;
    return refuse(instance, "fmi3GetVariableDependencies");
}

#define REFUSED_DERIVATIVE(NAME)                                                               \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, \
                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], \
                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)              \
    {                                                                                          \
        (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; \
        (void)sensitivity; (void)nSensitivity;                                                 \
        return refuse(instance, #NAME);                                                        \
    }

REFUSED_DERIVATIVE(fmi3GetDirectionalDerivative)
REFUSED_DERIVATIVE(fmi3GetAdjointDerivative)

#define REFUSED_PLAIN(NAME) \
    fmi3Status NAME(fmi3Instance instance) { return refuse(instance, #NAME); }

REFUSED_PLAIN(fmi3EnterConfigurationMode)
REFUSED_PLAIN(fmi3ExitConfigurationMode)
REFUSED_PLAIN(fmi3EvaluateDiscreteStates)
REFUSED_PLAIN(fmi3EnterContinuousTimeMode)

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
                                  size_t nvr, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[])
{
    (void)vr; (void)nvr; (void)intervals; (void)qualifiers;
    return refuse(instance, "fmi3GetIntervalDecimal");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions; (void)qualifiers;
    return refuse(instance, "fmi3GetIntervalFraction");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    (void)discreteStatesNeedUpdate; (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged; (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined; (void)nextEventTime;
    return refuse(instance, "fmi3UpdateDiscreteStates");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return refuse(instance, "fmi3CompletedIntegratorStep");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    return refuse(instance, "fmi3SetTime");
}

#define REFUSED_STATE_VECTOR(NAME, CONST)                                                      \
    fmi3Status NAME(fmi3Instance instance, CONST fmi3Float64 values[], size_t n)               \
    { (void)values; (void)n; return refuse(instance, #NAME); }

REFUSED_STATE_VECTOR(fmi3SetContinuousStates, const)
REFUSED_STATE_VECTOR(fmi3GetContinuousStateDerivatives, )
REFUSED_STATE_VECTOR(fmi3GetEventIndicators, )
REFUSED_STATE_VECTOR(fmi3GetContinuousStates, )
REFUSED_STATE_VECTOR(fmi3GetNominalsOfContinuousStates, )

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n)
{
    (void)n;
    return refuse(instance, "fmi3GetNumberOfEventIndicators");
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n)
{
    (void)n;
    return refuse(instance, "fmi3GetNumberOfContinuousStates");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference; (void)activationTime;
    return refuse(instance, "fmi3ActivateModelPartition");
}

#endif
