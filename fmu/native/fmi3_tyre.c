/* FMI 3.0 layer of the mftyre tyre FMUs (written for mftyre; see fmu/README.md): co-simulation and model exchange.
 *
 * It translates FMI 3.0 calls to the FMI 2.0 wrapper in the same binary (fmi2_tyre.c), which holds the one
 * implementation of the FMU's behaviour (phases, checks, messages, states, steps, derivatives): an FMI 3 instance
 * is an FMI 2 instance with the FMI 3 callbacks. The variables are the FMI 2 ones (all Float64, same value
 * references); the FMU has no clocks, no event mode in co-simulation and no scheduled execution.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "tyre_config.h"

typedef struct {
    fmi2Component c;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
    fmi2CallbackFunctions cb;
} Instance3;

#define I3(instance) ((Instance3 *)(instance))
#define C2(instance) (I3(instance)->c)
#define S3(status) ((fmi3Status)(status)) /* fmi2Status and fmi3Status number OK..Fatal alike */

/* The FMI 2 logger of the wrapper, forwarded to the FMI 3 callback (its environment is the Instance3). */
static void log2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                 fmi2String message, ...) {
    Instance3 *inst = (Instance3 *)env;
    char text[2048];
    va_list ap;
    (void)name;
    if (!inst || !inst->log) return;
    va_start(ap, message);
    vsnprintf(text, sizeof text, message, ap);
    va_end(ap);
    inst->log(inst->env, S3(status), category, text);
}

static void log3(Instance3 *inst, fmi3Status status, const char *fn, const char *why) {
    char text[512];
    if (!inst || !inst->log) return;
    snprintf(text, sizeof text, "%s: %s", fn, why);
    inst->log(inst->env, status, "logStatusError", text);
}

static fmi3Instance instantiate(fmi3String name, fmi3String token, fmi3Boolean visible, fmi3Boolean loggingOn,
                                fmi3InstanceEnvironment env, fmi3LogMessageCallback logMessage, fmi2Type type) {
    Instance3 *inst;
    if (!logMessage) return NULL;
    inst = (Instance3 *)calloc(1, sizeof(Instance3));
    if (!inst) {
        logMessage(env, fmi3Error, "logStatusError", "fmi3Instantiate: out of memory");
        return NULL;
    }
    inst->env = env;
    inst->log = logMessage;
    inst->cb.logger = log2;
    inst->cb.allocateMemory = calloc;
    inst->cb.freeMemory = free;
    inst->cb.componentEnvironment = inst;
    inst->c = fmi2Instantiate(name, type, token, "", &inst->cb, visible, loggingOn);
    if (!inst->c) {
        free(inst);
        return NULL;
    }
    return inst;
}

/* ------------------------------------------------------------------------------------------------ common */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    if (!instance) return fmi3Error;
    return S3(fmi2SetDebugLogging(C2(instance), loggingOn, nCategories, categories));
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)resourcePath;
    if (!TYRE_HAS_ME) {
        if (logMessage)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "fmi3InstantiateModelExchange: this FMU supports co-simulation only");
        return NULL;
    }
    return instantiate(instanceName, instantiationToken, visible, loggingOn, instanceEnvironment, logMessage,
                       fmi2ModelExchange);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)resourcePath, (void)earlyReturnAllowed, (void)requiredIntermediateVariables, (void)intermediateUpdate;
    if (eventModeUsed || nRequiredIntermediateVariables > 0) {
        if (logMessage)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "fmi3InstantiateCoSimulation: the FMU has no event mode and no intermediate variables "
                       "(hasEventMode = false)");
        return NULL;
    }
    return instantiate(instanceName, instantiationToken, visible, loggingOn, instanceEnvironment, logMessage,
                       fmi2CoSimulation);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: not provided (co-simulation and model exchange only)");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    if (!instance) return;
    fmi2FreeInstance(C2(instance));
    free(instance);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    fmi2Status s;
    if (!instance) return fmi3Error;
    s = fmi2SetupExperiment(C2(instance), toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime);
    return s > fmi2Warning ? S3(s) : S3(fmi2EnterInitializationMode(C2(instance)));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    return instance ? S3(fmi2ExitInitializationMode(C2(instance))) : fmi3Error;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    return instance ? S3(fmi2EnterEventMode(C2(instance))) : fmi3Error;
}

fmi3Status fmi3Terminate(fmi3Instance instance) { return instance ? S3(fmi2Terminate(C2(instance))) : fmi3Error; }

fmi3Status fmi3Reset(fmi3Instance instance) { return instance ? S3(fmi2Reset(C2(instance))) : fmi3Error; }

/* ------------------------------------------------------------------------------------------ get / set */
fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues) {
    if (!instance) return fmi3Error;
    if (nValues != nValueReferences) {
        log3(I3(instance), fmi3Error, "fmi3GetFloat64", "the FMU has scalar variables only (nValues must equal "
                                                         "nValueReferences)");
        return fmi3Error;
    }
    return S3(fmi2GetReal(C2(instance), valueReferences, nValueReferences, values));
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues) {
    if (!instance) return fmi3Error;
    if (nValues != nValueReferences) {
        log3(I3(instance), fmi3Error, "fmi3SetFloat64", "the FMU has scalar variables only (nValues must equal "
                                                         "nValueReferences)");
        return fmi3Error;
    }
    return S3(fmi2SetReal(C2(instance), valueReferences, nValueReferences, values));
}

/* The variable types the FMU does not have: an empty request is fine, any other an error. */
#define NO_VARIABLES(fn, type)                                                                                     \
    fmi3Status fn(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,      \
                  type values[], size_t nValues) {                                                                 \
        (void)valueReferences, (void)values, (void)nValues;                                                        \
        if (!instance) return fmi3Error;                                                                           \
        if (nValueReferences == 0) return fmi3OK;                                                                  \
        log3(I3(instance), fmi3Error, #fn, "unknown value reference (the FMU has only Float64 variables)");       \
        return fmi3Error;                                                                                          \
    }
NO_VARIABLES(fmi3GetFloat32, fmi3Float32)
NO_VARIABLES(fmi3GetInt8, fmi3Int8)
NO_VARIABLES(fmi3GetUInt8, fmi3UInt8)
NO_VARIABLES(fmi3GetInt16, fmi3Int16)
NO_VARIABLES(fmi3GetUInt16, fmi3UInt16)
NO_VARIABLES(fmi3GetInt32, fmi3Int32)
NO_VARIABLES(fmi3GetUInt32, fmi3UInt32)
NO_VARIABLES(fmi3GetInt64, fmi3Int64)
NO_VARIABLES(fmi3GetUInt64, fmi3UInt64)
NO_VARIABLES(fmi3GetBoolean, fmi3Boolean)
NO_VARIABLES(fmi3GetString, fmi3String)
NO_VARIABLES(fmi3SetFloat32, const fmi3Float32)
NO_VARIABLES(fmi3SetInt8, const fmi3Int8)
NO_VARIABLES(fmi3SetUInt8, const fmi3UInt8)
NO_VARIABLES(fmi3SetInt16, const fmi3Int16)
NO_VARIABLES(fmi3SetUInt16, const fmi3UInt16)
NO_VARIABLES(fmi3SetInt32, const fmi3Int32)
NO_VARIABLES(fmi3SetUInt32, const fmi3UInt32)
NO_VARIABLES(fmi3SetInt64, const fmi3Int64)
NO_VARIABLES(fmi3SetUInt64, const fmi3UInt64)
NO_VARIABLES(fmi3SetBoolean, const fmi3Boolean)
NO_VARIABLES(fmi3SetString, const fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)valueReferences, (void)valueSizes, (void)values, (void)nValues;
    if (!instance) return fmi3Error;
    if (nValueReferences == 0) return fmi3OK;
    log3(I3(instance), fmi3Error, "fmi3GetBinary", "unknown value reference (the FMU has only Float64 variables)");
    return fmi3Error;
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)valueReferences, (void)valueSizes, (void)values, (void)nValues;
    if (!instance) return fmi3Error;
    if (nValueReferences == 0) return fmi3OK;
    log3(I3(instance), fmi3Error, "fmi3SetBinary", "unknown value reference (the FMU has only Float64 variables)");
    return fmi3Error;
}

/* ------------------------------------------------------------------------- what the FMU does not have */
/* Each answers fmi3Error with the reason (the capability flags of the model description say so too). */
#define NOT_PROVIDED(fn, params, why)                                                                              \
    fmi3Status fn params {                                                                                         \
        if (!instance) return fmi3Error;                                                                           \
        log3(I3(instance), fmi3Error, #fn, why);                                                                   \
        return fmi3Error;                                                                                          \
    }
#define NO_CLOCKS "the FMU has no clocks"
NOT_PROVIDED(fmi3GetClock, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Clock v[]), NO_CLOCKS)
NOT_PROVIDED(fmi3SetClock, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Clock v[]),
             NO_CLOCKS)
NOT_PROVIDED(fmi3GetIntervalDecimal, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                      fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]), NO_CLOCKS)
NOT_PROVIDED(fmi3GetIntervalFraction, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                       fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                       fmi3IntervalQualifier qualifiers[]), NO_CLOCKS)
NOT_PROVIDED(fmi3GetShiftDecimal, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                   fmi3Float64 shifts[]), NO_CLOCKS)
NOT_PROVIDED(fmi3GetShiftFraction, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                    fmi3UInt64 counters[], fmi3UInt64 resolutions[]), NO_CLOCKS)
NOT_PROVIDED(fmi3SetIntervalDecimal, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                      const fmi3Float64 intervals[]), NO_CLOCKS)
NOT_PROVIDED(fmi3SetIntervalFraction, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                       const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]), NO_CLOCKS)
NOT_PROVIDED(fmi3SetShiftDecimal, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                   const fmi3Float64 shifts[]), NO_CLOCKS)
NOT_PROVIDED(fmi3SetShiftFraction, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                    const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]), NO_CLOCKS)
NOT_PROVIDED(fmi3ActivateModelPartition, (fmi3Instance instance, fmi3ValueReference clockReference,
                                          fmi3Float64 activationTime), "no scheduled execution")
NOT_PROVIDED(fmi3EnterConfigurationMode, (fmi3Instance instance), "the FMU has no structural parameters")
NOT_PROVIDED(fmi3ExitConfigurationMode, (fmi3Instance instance), "the FMU has no structural parameters")
NOT_PROVIDED(fmi3GetNumberOfVariableDependencies, (fmi3Instance instance, fmi3ValueReference valueReference,
                                                   size_t *nDependencies),
             "not provided: the model description lists the dependencies (ModelStructure)")
NOT_PROVIDED(fmi3GetVariableDependencies, (fmi3Instance instance, fmi3ValueReference dependent,
                                           size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                           size_t elementIndicesOfIndependents[],
                                           fmi3DependencyKind dependencyKinds[], size_t nDependencies),
             "not provided: the model description lists the dependencies (ModelStructure)")
NOT_PROVIDED(fmi3GetAdjointDerivative, (fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity),
             "not provided (providesAdjointDerivatives = false; directional derivatives are)")
NOT_PROVIDED(fmi3GetOutputDerivatives, (fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                        const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues),
             "not provided (maxOutputDerivativeOrder = 0)")
NOT_PROVIDED(fmi3EvaluateDiscreteStates, (fmi3Instance instance), "the FMU has no discrete states")

/* ------------------------------------------------------------------------------------------ FMU state */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return instance ? S3(fmi2GetFMUstate(C2(instance), FMUState)) : fmi3Error;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    return instance ? S3(fmi2SetFMUstate(C2(instance), FMUState)) : fmi3Error;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return instance ? S3(fmi2FreeFMUstate(C2(instance), FMUState)) : fmi3Error;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    return instance ? S3(fmi2SerializedFMUstateSize(C2(instance), FMUState, size)) : fmi3Error;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    return instance ? S3(fmi2SerializeFMUstate(C2(instance), FMUState, (fmi2Byte *)serializedState, size))
                    : fmi3Error;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    return instance ? S3(fmi2DeSerializeFMUstate(C2(instance), (const fmi2Byte *)serializedState, size, FMUState))
                    : fmi3Error;
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    if (!instance) return fmi3Error;
    if (nSeed != nKnowns || nSensitivity != nUnknowns) {
        log3(I3(instance), fmi3Error, "fmi3GetDirectionalDerivative",
             "the FMU has scalar variables only (nSeed = nKnowns, nSensitivity = nUnknowns)");
        return fmi3Error;
    }
    return S3(fmi2GetDirectionalDerivative(C2(instance), unknowns, nUnknowns, knowns, nKnowns, seed, sensitivity));
}

/* ------------------------------------------------------------------------------------- model exchange */
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    fmi2EventInfo info;
    fmi2Status s;
    if (!instance) return fmi3Error;
    s = fmi2NewDiscreteStates(C2(instance), &info);
    if (s > fmi2Warning) return S3(s);
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = info.newDiscreteStatesNeeded != fmi2False;
    if (terminateSimulation) *terminateSimulation = info.terminateSimulation != fmi2False;
    if (nominalsOfContinuousStatesChanged)
        *nominalsOfContinuousStatesChanged = info.nominalsOfContinuousStatesChanged != fmi2False;
    if (valuesOfContinuousStatesChanged)
        *valuesOfContinuousStatesChanged = info.valuesOfContinuousStatesChanged != fmi2False;
    if (nextEventTimeDefined) *nextEventTimeDefined = info.nextEventTimeDefined != fmi2False;
    if (nextEventTime) *nextEventTime = info.nextEventTime;
    return S3(s);
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    return instance ? S3(fmi2EnterContinuousTimeMode(C2(instance))) : fmi3Error;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    fmi2Boolean enter = fmi2False, stop = fmi2False;
    fmi2Status s;
    if (!instance) return fmi3Error;
    s = fmi2CompletedIntegratorStep(C2(instance), noSetFMUStatePriorToCurrentPoint, &enter, &stop);
    if (enterEventMode) *enterEventMode = enter != fmi2False;
    if (terminateSimulation) *terminateSimulation = stop != fmi2False;
    return S3(s);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    return instance ? S3(fmi2SetTime(C2(instance), time)) : fmi3Error;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    return instance ? S3(fmi2SetContinuousStates(C2(instance), continuousStates, nContinuousStates)) : fmi3Error;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    return instance ? S3(fmi2GetDerivatives(C2(instance), derivatives, nContinuousStates)) : fmi3Error;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    return instance ? S3(fmi2GetEventIndicators(C2(instance), eventIndicators, nEventIndicators)) : fmi3Error;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    return instance ? S3(fmi2GetContinuousStates(C2(instance), continuousStates, nContinuousStates)) : fmi3Error;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    return instance ? S3(fmi2GetNominalsOfContinuousStates(C2(instance), nominals, nContinuousStates)) : fmi3Error;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    if (!instance || !nEventIndicators) return fmi3Error;
    *nEventIndicators = TYRE_NZ;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    if (!instance || !nContinuousStates) return fmi3Error;
    *nContinuousStates = TYRE_NX;
    return fmi3OK;
}

/* --------------------------------------------------------------------------------------- co-simulation */
fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    return instance ? fmi3OK : fmi3Error; /* co-simulation without event mode is in step mode after initialisation */
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    fmi2Status s;
    if (!instance) return fmi3Error;
    s = fmi2DoStep(C2(instance), currentCommunicationPoint, communicationStepSize, noSetFMUStatePriorToCurrentPoint);
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastSuccessfulTime)
        *lastSuccessfulTime = s == fmi2OK || s == fmi2Warning ? currentCommunicationPoint + communicationStepSize
                                                              : currentCommunicationPoint;
    return S3(s);
}
