/* FMI 2.0 co-simulation and model exchange wrapper of the mftyre tyre models (written for mftyre; see
 * fmu/README.md; fmi3_tyre.c is the FMI 3.0 layer over it).
 *
 * It only translates FMI calls: the tyre is the model glue (tyre_glue.h: glue_init, glue_step, glue_out,
 * glue_dout, glue_validate), which calls the C code CasADi generated from mftyre's equations. Variables:
 * value references 0..NQ-1 are the parameters q, NQ..NQ+NU-1 the inputs u, then the NY outputs y (the states x
 * are outputs too: TYRE_X_OUTPUT), then for model exchange the NX state derivatives and the NZ event indicators, then
 * time (FMI 3's independent variable). The whole
 * internal state (phase, time, q, u, x, y) is one plain struct, so FMU states are copies of it and serialise
 * byte for byte. Every failure is logged with its cause and reported through the status; nothing aborts.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "tyre_config.h"
#include "tyre_glue.h"

#define N_VARS (TYRE_NQ + TYRE_NU + TYRE_NY)
#define N_DER (TYRE_HAS_ME ? TYRE_NX : 0) /* the state derivatives have variables in model exchange */
#define N_ALL (N_VARS + N_DER + TYRE_NZ)
#define ARR(n) ((n) > 0 ? (n) : 1)
#define STATE_MAGIC 0x6d667479u /* "mfty" */

typedef enum { PHASE_INSTANTIATED, PHASE_INIT, PHASE_STEP, PHASE_TERMINATED, PHASE_ERROR } Phase;

typedef struct {
    unsigned magic;
    unsigned size;
    char guid[sizeof(TYRE_GUID)]; /* a state of this FMU only (same model, same .tir) */
    int phase;
    int outputs_valid; /* y belongs to the current (x, u) */
    double time;
    double q[ARR(TYRE_NQ)];
    double u[ARR(TYRE_NU)];
    double x[ARR(TYRE_NX)];
    double y[ARR(TYRE_NY)];
} TyreState;

typedef struct {
    fmi2CallbackFunctions cb;
    char *name;
    int logging;
    int me; /* instantiated for model exchange */
    TyreState s;
    GlueWork *work;
} Instance;

static void logf_(Instance *inst, fmi2Status status, const char *category, const char *fmt, ...) {
    char msg[2048];
    va_list ap;
    if (!inst || !inst->cb.logger) return;
    if (!inst->logging && status == fmi2OK) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    inst->cb.logger(inst->cb.componentEnvironment, inst->name, status, category, "%s", msg);
}

#define LOG_ERROR(inst, ...) logf_((inst), fmi2Error, "logStatusError", __VA_ARGS__)
#define LOG_DISCARD(inst, ...) logf_((inst), fmi2Discard, "logStatusDiscard", __VA_ARGS__)

static void reset_values(Instance *inst) {
    memset(&inst->s, 0, sizeof inst->s);
    inst->s.magic = STATE_MAGIC;
    inst->s.size = (unsigned)sizeof(TyreState);
    memcpy(inst->s.guid, TYRE_GUID, sizeof(TYRE_GUID));
    inst->s.phase = PHASE_INSTANTIATED;
    for (int i = 0; i < TYRE_NQ; i++) inst->s.q[i] = TYRE_Q_START[i];
    for (int i = 0; i < TYRE_NU; i++) inst->s.u[i] = TYRE_U_START[i];
}

static int all_finite(const double *v, int n) {
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* Check q and u; on failure the message names the variable. */
static int check_values(Instance *inst, char *msg, size_t n) {
    for (int i = 0; i < TYRE_NQ; i++)
        if (!isfinite(inst->s.q[i])) {
            snprintf(msg, n, "parameter %s is not finite (%g)", TYRE_Q_NAMES[i], inst->s.q[i]);
            return 0;
        }
    for (int i = 0; i < TYRE_NU; i++)
        if (!isfinite(inst->s.u[i])) {
            snprintf(msg, n, "input %s is not finite (%g)", TYRE_U_NAMES[i], inst->s.u[i]);
            return 0;
        }
    return glue_validate(inst->s.q, inst->s.u, msg, n) == 0;
}

/* y = out(x, u) unless y is already current; on failure the old outputs are kept. In initialisation mode x is
 * the initial state the current parameters and inputs give. */
static fmi2Status update_outputs(Instance *inst, const char *caller) {
    char msg[1024];
    double y[ARR(TYRE_NY)], x0[ARR(TYRE_NX)];
    const double *x = inst->s.x;
    if (inst->s.outputs_valid || inst->s.phase == PHASE_INSTANTIATED) return fmi2OK;
    if (!check_values(inst, msg, sizeof msg)) {
        LOG_DISCARD(inst, "%s: %s; outputs held at their last values", caller, msg);
        return fmi2Discard;
    }
    if (inst->s.phase == PHASE_INIT) {
        msg[0] = 0;
        if (glue_init(inst->work, inst->s.u, inst->s.q, x0, msg, sizeof msg) != 0) {
            LOG_DISCARD(inst, "%s: %s", caller, msg[0] ? msg : "no initial state at these inputs");
            return fmi2Discard;
        }
        x = x0;
    }
    if (glue_out(inst->work, x, inst->s.u, inst->s.q, y) != 0 || !all_finite(y, TYRE_NY)) {
        LOG_DISCARD(inst, "%s: the tyre outputs are not finite at these inputs; outputs held", caller);
        return fmi2Discard;
    }
    memcpy(inst->s.y, y, sizeof y);
    inst->s.outputs_valid = 1;
    return fmi2OK;
}

static Instance *as_instance(fmi2Component c) { return (Instance *)c; }

#define CHECK_INSTANCE(c, fn)                                                                                      \
    Instance *inst = as_instance(c);                                                                               \
    if (!inst) return fmi2Error;                                                                                   \
    if (inst->s.phase == PHASE_ERROR && strcmp(fn, "fmi2GetReal") != 0) {                                         \
        LOG_ERROR(inst, "%s: the instance is in the error state (call fmi2Reset or fmi2FreeInstance)", fn);      \
        return fmi2Error;                                                                                          \
    }

/* ------------------------------------------------------------------------------------------------ common */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    Instance *inst = as_instance(c);
    (void)nCategories;
    (void)categories;
    if (!inst) return fmi2Error;
    inst->logging = loggingOn ? 1 : 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    Instance *inst;
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions || !functions->logger) return NULL;
#define FAIL(...)                                                                                                  \
    do {                                                                                                           \
        functions->logger(functions->componentEnvironment, instanceName ? instanceName : "?", fmi2Error,        \
                          "logStatusError", __VA_ARGS__);                                                          \
        return NULL;                                                                                               \
    } while (0)
    if (!instanceName || !instanceName[0]) FAIL("fmi2Instantiate: the instance name is empty");
    if (fmuType != fmi2CoSimulation && !(TYRE_HAS_ME && fmuType == fmi2ModelExchange))
        FAIL("fmi2Instantiate: this FMU supports co-simulation only");
    if (!fmuGUID || strcmp(fmuGUID, TYRE_GUID) != 0)
        FAIL("fmi2Instantiate: GUID %s does not match the FMU's %s", fmuGUID ? fmuGUID : "(null)", TYRE_GUID);
    inst = (Instance *)calloc(1, sizeof(Instance));
    if (!inst) FAIL("fmi2Instantiate: out of memory");
    inst->name = (char *)malloc(strlen(instanceName) + 1);
    inst->work = glue_alloc();
    if (!inst->name || !inst->work) {
        free(inst->name);
        glue_free(inst->work);
        free(inst);
        FAIL("fmi2Instantiate: out of memory");
    }
#undef FAIL
    strcpy(inst->name, instanceName);
    inst->cb = *functions;
    inst->logging = loggingOn ? 1 : 0;
    inst->me = fmuType == fmi2ModelExchange;
    reset_values(inst);
    return inst;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance *inst = as_instance(c);
    if (!inst) return;
    glue_free(inst->work);
    free(inst->name);
    free(inst);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    CHECK_INSTANCE(c, "fmi2SetupExperiment")
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (inst->s.phase != PHASE_INSTANTIATED) {
        LOG_ERROR(inst, "fmi2SetupExperiment: only allowed after fmi2Instantiate");
        return fmi2Error;
    }
    if (!isfinite(startTime)) {
        LOG_ERROR(inst, "fmi2SetupExperiment: start time %g is not finite", startTime);
        return fmi2Error;
    }
    inst->s.time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    CHECK_INSTANCE(c, "fmi2EnterInitializationMode")
    if (inst->s.phase != PHASE_INSTANTIATED) {
        LOG_ERROR(inst, "fmi2EnterInitializationMode: only allowed after fmi2Instantiate/fmi2SetupExperiment");
        return fmi2Error;
    }
    inst->s.phase = PHASE_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    char msg[1024];
    double x[ARR(TYRE_NX)];
    CHECK_INSTANCE(c, "fmi2ExitInitializationMode")
    if (inst->s.phase != PHASE_INIT) {
        LOG_ERROR(inst, "fmi2ExitInitializationMode: not in initialisation mode");
        return fmi2Error;
    }
    if (!check_values(inst, msg, sizeof msg)) {
        inst->s.phase = PHASE_ERROR;
        LOG_ERROR(inst, "initialisation failed: %s", msg);
        return fmi2Error;
    }
    msg[0] = 0;
    if (glue_init(inst->work, inst->s.u, inst->s.q, x, msg, sizeof msg) != 0 || !all_finite(x, TYRE_NX)) {
        inst->s.phase = PHASE_ERROR;
        LOG_ERROR(inst, "initialisation failed: %s", msg[0] ? msg : "the initial state is not finite");
        return fmi2Error;
    }
    memcpy(inst->s.x, x, sizeof x);
    inst->s.phase = PHASE_STEP;
    inst->s.outputs_valid = 0;
    if (update_outputs(inst, "fmi2ExitInitializationMode") != fmi2OK) {
        inst->s.phase = PHASE_ERROR;
        LOG_ERROR(inst, "initialisation failed: the outputs at the initial inputs are not finite");
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    CHECK_INSTANCE(c, "fmi2Terminate")
    inst->s.phase = PHASE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Instance *inst = as_instance(c);
    if (!inst) return fmi2Error;
    reset_values(inst);
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ get / set */
typedef enum { VAR_PARAMETER, VAR_INPUT, VAR_OUTPUT, VAR_DERIVATIVE, VAR_EVENT, VAR_TIME, VAR_UNKNOWN } VarKind;

/* What value reference r names, and through *index its place in q, u or y. */
static VarKind var_kind(fmi2ValueReference r, size_t *index) {
    if (r < TYRE_NQ) {
        *index = r;
        return VAR_PARAMETER;
    }
    if (r < TYRE_NQ + TYRE_NU) {
        *index = r - TYRE_NQ;
        return VAR_INPUT;
    }
    if (r < N_VARS) {
        *index = r - TYRE_NQ - TYRE_NU;
        return VAR_OUTPUT;
    }
    if (r < N_VARS + N_DER) {
        *index = r - N_VARS;
        return VAR_DERIVATIVE;
    }
    if (r < N_ALL) {
        *index = r - N_VARS - N_DER;
        return VAR_EVENT;
    }
    *index = 0;
    return r == N_ALL ? VAR_TIME : VAR_UNKNOWN; /* the independent variable of FMI 3 */
}

/* The arrays of a get/set call: vr and value must be given when nvr > 0 (else an error naming fn). */
static int arrays_given(Instance *inst, const char *fn, size_t nvr, const void *vr, const void *value) {
    if (nvr > 0 && (!vr || !value)) {
        LOG_ERROR(inst, "%s: null value reference or value array for %lu variables", fn, (unsigned long)nvr);
        return 0;
    }
    return 1;
}

static fmi2Status me_values(Instance *inst, const char *caller, double *xdot, double *z);

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    fmi2Status status = fmi2OK;
    size_t k;
    double xdot[ARR(TYRE_NX)] = {0}, z[ARR(TYRE_NZ)] = {0};
    int me_done = 0;
    CHECK_INSTANCE(c, "fmi2GetReal")
    if (!arrays_given(inst, "fmi2GetReal", nvr, vr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++)
        if (var_kind(vr[i], &k) == VAR_OUTPUT && inst->s.phase != PHASE_ERROR) {
            status = update_outputs(inst, "fmi2GetReal");
            break;
        }
    for (size_t i = 0; i < nvr; i++) {
        VarKind kind = var_kind(vr[i], &k);
        if ((kind == VAR_DERIVATIVE || kind == VAR_EVENT) && !me_done) {
            if (me_values(inst, "fmi2GetReal", xdot, z) != fmi2OK) return fmi2Error;
            me_done = 1;
        }
        switch (kind) {
        case VAR_PARAMETER: value[i] = inst->s.q[k]; break;
        case VAR_INPUT: value[i] = inst->s.u[k]; break;
        case VAR_OUTPUT: value[i] = inst->s.y[k]; break;
        case VAR_DERIVATIVE: value[i] = xdot[k]; break;
        case VAR_EVENT: value[i] = z[k]; break;
        case VAR_TIME: value[i] = inst->s.time; break;
        default:
            LOG_ERROR(inst, "fmi2GetReal: unknown value reference %u", (unsigned)vr[i]);
            return fmi2Error;
        }
    }
    return status == fmi2Discard ? fmi2Warning : status;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    size_t k;
    CHECK_INSTANCE(c, "fmi2SetReal")
    if (!arrays_given(inst, "fmi2SetReal", nvr, vr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        switch (var_kind(vr[i], &k)) {
        case VAR_PARAMETER:
            if (inst->s.phase != PHASE_INSTANTIATED && inst->s.phase != PHASE_INIT) {
                LOG_ERROR(inst, "fmi2SetReal: parameter %s is fixed after initialisation", TYRE_Q_NAMES[k]);
                return fmi2Error;
            }
            inst->s.q[k] = value[i];
            break;
        case VAR_INPUT: inst->s.u[k] = value[i]; break;
        default:
            LOG_ERROR(inst, "fmi2SetReal: value reference %u is not a parameter or an input", (unsigned)vr[i]);
            return fmi2Error;
        }
        inst->s.outputs_valid = 0;
    }
    return fmi2OK;
}

#define NO_VARIABLES(fn, type)                                                                                     \
    fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, type value[]) {                    \
        CHECK_INSTANCE(c, #fn)                                                                                     \
        if (!arrays_given(inst, #fn, nvr, vr, value)) return fmi2Error;                                           \
        if (nvr == 0) return fmi2OK;                                                                               \
        LOG_ERROR(inst, #fn ": unknown value reference %u (the FMU has only Real variables)", (unsigned)vr[0]); \
        return fmi2Error;                                                                                          \
    }
NO_VARIABLES(fmi2GetInteger, fmi2Integer)
NO_VARIABLES(fmi2GetBoolean, fmi2Boolean)
NO_VARIABLES(fmi2GetString, fmi2String)
NO_VARIABLES(fmi2SetInteger, const fmi2Integer)
NO_VARIABLES(fmi2SetBoolean, const fmi2Boolean)
NO_VARIABLES(fmi2SetString, const fmi2String)

/* ------------------------------------------------------------------------------------------ FMU state */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    TyreState *copy;
    CHECK_INSTANCE(c, "fmi2GetFMUstate")
    if (!FMUstate) return fmi2Error;
    copy = (TyreState *)(*FMUstate ? *FMUstate : malloc(sizeof(TyreState)));
    if (!copy) {
        LOG_ERROR(inst, "fmi2GetFMUstate: out of memory");
        return fmi2Error;
    }
    *copy = inst->s;
    *FMUstate = copy;
    return fmi2OK;
}

static int valid_state(const TyreState *s) {
    return s && s->magic == STATE_MAGIC && s->size == sizeof(TyreState) &&
           memcmp(s->guid, TYRE_GUID, sizeof(TYRE_GUID)) == 0;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    CHECK_INSTANCE(c, "fmi2SetFMUstate")
    if (!valid_state((const TyreState *)FMUstate)) {
        LOG_ERROR(inst, "fmi2SetFMUstate: not a state of this FMU");
        return fmi2Error;
    }
    inst->s = *(const TyreState *)FMUstate;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    (void)c;
    if (FMUstate && *FMUstate) {
        free(*FMUstate);
        *FMUstate = NULL;
    }
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    CHECK_INSTANCE(c, "fmi2SerializedFMUstateSize")
    (void)FMUstate;
    if (!size) return fmi2Error;
    *size = sizeof(TyreState) + sizeof(TYRE_GUID);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    CHECK_INSTANCE(c, "fmi2SerializeFMUstate")
    if (!valid_state((const TyreState *)FMUstate) || !serializedState || size < sizeof(TyreState) + sizeof(TYRE_GUID)) {
        LOG_ERROR(inst, "fmi2SerializeFMUstate: invalid state or buffer of %lu bytes (need %lu)",
                  (unsigned long)size, (unsigned long)(sizeof(TyreState) + sizeof(TYRE_GUID)));
        return fmi2Error;
    }
    memcpy(serializedState, TYRE_GUID, sizeof(TYRE_GUID));
    memcpy(serializedState + sizeof(TYRE_GUID), FMUstate, sizeof(TyreState));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    TyreState tmp, *copy;
    CHECK_INSTANCE(c, "fmi2DeSerializeFMUstate")
    if (!serializedState || !FMUstate || size != sizeof(TyreState) + sizeof(TYRE_GUID) ||
        memcmp(serializedState, TYRE_GUID, sizeof(TYRE_GUID)) != 0) {
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: the bytes are not a serialised state of this FMU");
        return fmi2Error;
    }
    memcpy(&tmp, serializedState + sizeof(TYRE_GUID), sizeof tmp);
    if (!valid_state(&tmp)) {
        LOG_ERROR(inst, "fmi2DeSerializeFMUstate: corrupt state");
        return fmi2Error;
    }
    copy = (TyreState *)(*FMUstate ? *FMUstate : malloc(sizeof(TyreState)));
    if (!copy) return fmi2Error;
    *copy = tmp;
    *FMUstate = copy;
    return fmi2OK;
}

/* ------------------------------------------------------------------------------- directional derivative */
/* The state whose variable is output k, or -1. */
static int state_of_output(size_t k) {
    for (int i = 0; i < TYRE_NX; i++)
        if ((size_t)TYRE_X_OUTPUT[i] == k) return i;
    return -1;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    char msg[1024];
    double du[ARR(TYRE_NU)] = {0}, dy[ARR(TYRE_NY)], dx[ARR(TYRE_NX)] = {0}, dxdot[ARR(TYRE_NX)];
    size_t k;
    int xk;
    CHECK_INSTANCE(c, "fmi2GetDirectionalDerivative")
    if ((nKnown > 0 && (!vKnown_ref || !dvKnown)) || (nUnknown > 0 && (!vUnknown_ref || !dvUnknown))) {
        LOG_ERROR(inst, "fmi2GetDirectionalDerivative: null argument");
        return fmi2Error;
    }
    if (!TYRE_HAS_DD) {
        LOG_ERROR(inst, "fmi2GetDirectionalDerivative: not provided by this model");
        return fmi2Error;
    }
    if (inst->s.phase != PHASE_STEP) {
        LOG_ERROR(inst, "fmi2GetDirectionalDerivative: only after initialisation");
        return fmi2Error;
    }
    for (size_t i = 0; i < nKnown; i++) {
        VarKind kind = var_kind(vKnown_ref[i], &k);
        if (kind == VAR_OUTPUT && inst->me && (xk = state_of_output(k)) >= 0) {
            dx[xk] += dvKnown[i];
            continue;
        }
        if (kind != VAR_INPUT) {
            LOG_ERROR(inst, "fmi2GetDirectionalDerivative: known %u is not an input%s", (unsigned)vKnown_ref[i],
                      inst->me ? " or a state" : "");
            return fmi2Error;
        }
        du[k] += dvKnown[i];
    }
    for (size_t i = 0; i < nUnknown; i++) {
        VarKind kind = var_kind(vUnknown_ref[i], &k);
        if (kind != VAR_OUTPUT && !(kind == VAR_DERIVATIVE && inst->me)) {
            LOG_ERROR(inst, "fmi2GetDirectionalDerivative: unknown %u is not an output%s", (unsigned)vUnknown_ref[i],
                      inst->me ? " or a state derivative" : "");
            return fmi2Error;
        }
    }
    /* as fmi2DoStep: no derivative at inputs or parameters it refuses; none that is not finite */
    if (!all_finite(du, TYRE_NU) || !all_finite(dx, TYRE_NX)) {
        LOG_ERROR(inst, "fmi2GetDirectionalDerivative: a seed dvKnown is not finite");
        return fmi2Error;
    }
    if (!check_values(inst, msg, sizeof msg)) {
        LOG_DISCARD(inst, "fmi2GetDirectionalDerivative: %s; no derivative", msg);
        return fmi2Discard;
    }
    if (glue_dout(inst->work, inst->s.x, inst->s.u, inst->s.q, dx, du, dy, dxdot) != 0) {
        LOG_ERROR(inst, "fmi2GetDirectionalDerivative: evaluation failed");
        return fmi2Error;
    }
    if (!all_finite(dy, TYRE_NY) || !all_finite(dxdot, TYRE_NX)) {
        LOG_DISCARD(inst, "fmi2GetDirectionalDerivative: the derivative is not finite at these inputs");
        return fmi2Discard;
    }
    for (size_t i = 0; i < nUnknown; i++)
        dvUnknown[i] = var_kind(vUnknown_ref[i], &k) == VAR_DERIVATIVE ? dxdot[k] : dy[k];
    return fmi2OK;
}

/* --------------------------------------------------------------------------------------- co-simulation */
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    char msg[1024];
    double x[ARR(TYRE_NX)];
    fmi2Status status;
    int rc;
    CHECK_INSTANCE(c, "fmi2DoStep")
    (void)noSetFMUStatePriorToCurrentPoint;
    if (inst->me) {
        LOG_ERROR(inst, "fmi2DoStep: the instance is a model exchange instance (the host integrates)");
        return fmi2Error;
    }
    if (inst->s.phase != PHASE_STEP) {
        LOG_ERROR(inst, "fmi2DoStep: not in step mode (initialise first)");
        return fmi2Error;
    }
    if (!isfinite(t) || !isfinite(h) || !(h > 0.0)) {
        LOG_DISCARD(inst, "fmi2DoStep: step size %g at t = %g rejected (must be positive and finite); state and "
                          "outputs held", h, t);
        return fmi2Discard;
    }
    if (!check_values(inst, msg, sizeof msg)) {
        LOG_DISCARD(inst, "fmi2DoStep at t = %g: %s; state and outputs held", t, msg);
        return fmi2Discard;
    }
    memcpy(x, inst->s.x, sizeof x);
    rc = glue_step(inst->work, x, inst->s.u, inst->s.q, h);
    if (rc == GLUE_OVER_BUDGET) {
        LOG_ERROR(inst, "fmi2DoStep at t = %g: the step of %g s needs more internal steps than its time budget "
                        "(the parameter max_step is too small, the speed too high or the step too long for this "
                        "model: split it); state and outputs held", t, h);
        return fmi2Error;
    }
    if (rc != 0 || !all_finite(x, TYRE_NX)) {
        LOG_DISCARD(inst, "fmi2DoStep at t = %g: the tyre state became non-finite; state and outputs held", t);
        return fmi2Discard;
    }
    {
        TyreState saved = inst->s;
        memcpy(inst->s.x, x, sizeof x);
        inst->s.outputs_valid = 0;
        status = update_outputs(inst, "fmi2DoStep");
        if (status != fmi2OK) {
            inst->s = saved;
            return status;
        }
    }
    inst->s.time = t + h;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    CHECK_INSTANCE(c, "fmi2CancelStep")
    LOG_ERROR(inst, "fmi2CancelStep: steps are synchronous (canRunAsynchronuously = false)");
    return fmi2Error;
}

/* The calls for what this FMU does not provide (FMI 2.0 capability flags false): a non-empty request is an error. */
#define NOT_PROVIDED(fn, type, why)                                                                                \
    fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer order[],         \
                  type value[]) {                                                                                  \
        CHECK_INSTANCE(c, #fn)                                                                                     \
        (void)vr;                                                                                                  \
        (void)order;                                                                                               \
        (void)value;                                                                                               \
        if (nvr == 0) return fmi2OK;                                                                               \
        LOG_ERROR(inst, #fn ": " why);                                                                             \
        return fmi2Error;                                                                                          \
    }
NOT_PROVIDED(fmi2SetRealInputDerivatives, const fmi2Real,
             "inputs are held constant over a step (canInterpolateInputs = false)")
NOT_PROVIDED(fmi2GetRealOutputDerivatives, fmi2Real, "not provided (MaxOutputDerivativeOrder = 0)")

/* Status of an asynchronous step: there is none (canRunAsynchronuously = false), except the last successful time
 * and the terminated flag, which a co-simulation master may ask for at any time. */
#define STATUS(fn, type, kind, answer)                                                                             \
    fmi2Status fn(fmi2Component c, const fmi2StatusKind s, type *value) {                                          \
        CHECK_INSTANCE(c, #fn)                                                                                     \
        if (s == (kind) && value) {                                                                                \
            *value = (answer);                                                                                     \
            return fmi2OK;                                                                                         \
        }                                                                                                          \
        LOG_DISCARD(inst, #fn ": no asynchronous step is running; no status to report");                          \
        return fmi2Discard;                                                                                        \
    }
#define NO_KIND ((fmi2StatusKind)-1)
STATUS(fmi2GetStatus, fmi2Status, NO_KIND, fmi2OK)
STATUS(fmi2GetRealStatus, fmi2Real, fmi2LastSuccessfulTime, inst->s.time)
STATUS(fmi2GetIntegerStatus, fmi2Integer, NO_KIND, 0)
STATUS(fmi2GetBooleanStatus, fmi2Boolean, fmi2Terminated, fmi2False)
STATUS(fmi2GetStringStatus, fmi2String, NO_KIND, NULL)

/* ------------------------------------------------------------------------------------- model exchange */
/* The host's integrator holds the states: it sets x (fmi2SetContinuousStates) and the time, and takes the
 * derivatives of the tyre's state equations (glue_deriv) and the event indicators (glue_events: a sign change marks
 * a switch of the equations: direction of travel, low speed, contact). The equations have no discrete states, so
 * events need no update. */
static int me_ready(Instance *inst, const char *fn) {
    if (!inst->me) {
        LOG_ERROR(inst, "%s: the instance is a co-simulation instance", fn);
        return 0;
    }
    if (inst->s.phase != PHASE_STEP && inst->s.phase != PHASE_INIT) {
        LOG_ERROR(inst, "%s: only in initialisation, event or continuous-time mode", fn);
        return 0;
    }
    return 1;
}

/* xdot and z at the current (x, u); in initialisation mode at the initial state of the current inputs. */
static fmi2Status me_values(Instance *inst, const char *caller, double *xdot, double *z) {
    char msg[1024];
    double x0[ARR(TYRE_NX)];
    const double *x = inst->s.x;
    if (!me_ready(inst, caller)) return fmi2Error;
    if (!check_values(inst, msg, sizeof msg)) {
        LOG_ERROR(inst, "%s: %s", caller, msg);
        return fmi2Error;
    }
    if (inst->s.phase == PHASE_INIT) {
        msg[0] = 0;
        if (glue_init(inst->work, inst->s.u, inst->s.q, x0, msg, sizeof msg) != 0) {
            LOG_ERROR(inst, "%s: %s", caller, msg[0] ? msg : "no initial state at these inputs");
            return fmi2Error;
        }
        x = x0;
    }
    if ((xdot && TYRE_NX > 0 && (glue_deriv(inst->work, x, inst->s.u, inst->s.q, xdot) != 0 ||
                                 !all_finite(xdot, TYRE_NX))) ||
        (z && TYRE_NZ > 0 && (glue_events(inst->work, x, inst->s.u, inst->s.q, z) != 0 || !all_finite(z, TYRE_NZ)))) {
        LOG_ERROR(inst, "%s: the state derivatives or event indicators are not finite at this state and these inputs",
                  caller);
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    CHECK_INSTANCE(c, "fmi2EnterEventMode")
    return me_ready(inst, "fmi2EnterEventMode") ? fmi2OK : fmi2Error;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    CHECK_INSTANCE(c, "fmi2NewDiscreteStates")
    if (!me_ready(inst, "fmi2NewDiscreteStates") || !info) return fmi2Error;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    CHECK_INSTANCE(c, "fmi2EnterContinuousTimeMode")
    return me_ready(inst, "fmi2EnterContinuousTimeMode") ? fmi2OK : fmi2Error;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    CHECK_INSTANCE(c, "fmi2CompletedIntegratorStep")
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!me_ready(inst, "fmi2CompletedIntegratorStep") || !enterEventMode || !terminateSimulation) return fmi2Error;
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    CHECK_INSTANCE(c, "fmi2SetTime")
    if (!me_ready(inst, "fmi2SetTime")) return fmi2Error;
    if (!isfinite(time)) {
        LOG_ERROR(inst, "fmi2SetTime: time %g is not finite", time);
        return fmi2Error;
    }
    inst->s.time = time;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    CHECK_INSTANCE(c, "fmi2SetContinuousStates")
    if (!me_ready(inst, "fmi2SetContinuousStates")) return fmi2Error;
    if (nx != TYRE_NX || (nx > 0 && !x)) {
        LOG_ERROR(inst, "fmi2SetContinuousStates: %lu states given, the FMU has %d", (unsigned long)nx, TYRE_NX);
        return fmi2Error;
    }
    if (!all_finite(x, (int)nx)) {
        LOG_ERROR(inst, "fmi2SetContinuousStates: a state is not finite");
        return fmi2Error;
    }
    for (size_t i = 0; i < nx; i++) inst->s.x[i] = x[i];
    inst->s.outputs_valid = 0;
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    char msg[1024];
    CHECK_INSTANCE(c, "fmi2GetContinuousStates")
    if (!me_ready(inst, "fmi2GetContinuousStates")) return fmi2Error;
    if (nx != TYRE_NX || (nx > 0 && !x)) {
        LOG_ERROR(inst, "fmi2GetContinuousStates: %lu states asked for, the FMU has %d", (unsigned long)nx, TYRE_NX);
        return fmi2Error;
    }
    if (inst->s.phase == PHASE_INIT) { /* the initial state of the current inputs */
        msg[0] = 0;
        if (!check_values(inst, msg, sizeof msg) ||
            glue_init(inst->work, inst->s.u, inst->s.q, x, msg, sizeof msg) != 0) {
            LOG_ERROR(inst, "fmi2GetContinuousStates: %s", msg[0] ? msg : "no initial state at these inputs");
            return fmi2Error;
        }
        return fmi2OK;
    }
    for (size_t i = 0; i < nx; i++) x[i] = inst->s.x[i];
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    CHECK_INSTANCE(c, "fmi2GetNominalsOfContinuousStates")
    if (nx != TYRE_NX || (nx > 0 && !x_nominal)) {
        LOG_ERROR(inst, "fmi2GetNominalsOfContinuousStates: %lu states asked for, the FMU has %d", (unsigned long)nx,
                  TYRE_NX);
        return fmi2Error;
    }
    for (size_t i = 0; i < nx; i++) x_nominal[i] = TYRE_X_NOMINAL;
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    CHECK_INSTANCE(c, "fmi2GetDerivatives")
    if (nx != TYRE_NX || (nx > 0 && !derivatives)) {
        LOG_ERROR(inst, "fmi2GetDerivatives: %lu derivatives asked for, the FMU has %d states", (unsigned long)nx,
                  TYRE_NX);
        return fmi2Error;
    }
    return me_values(inst, "fmi2GetDerivatives", derivatives, NULL);
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    CHECK_INSTANCE(c, "fmi2GetEventIndicators")
    if (ni != TYRE_NZ || (ni > 0 && !eventIndicators)) {
        LOG_ERROR(inst, "fmi2GetEventIndicators: %lu indicators asked for, the FMU has %d", (unsigned long)ni,
                  TYRE_NZ);
        return fmi2Error;
    }
    return me_values(inst, "fmi2GetEventIndicators", NULL, eventIndicators);
}
