/*
 * corpus_fmu.c - every function of fmi3Functions.h for the corpus models:
 * small, valid FMI 3.0 FMUs (Model Exchange, Co-Simulation, Scheduled
 * Execution) that do not use the fmi-ls-dae layer. One model file supplies
 * `const ModelDef MODEL` (corpus_model.h).
 *
 * What it does, simply:
 *  - values live in typed pools (Float32/64 as double, signed integers and
 *    Enumerations as int64, unsigned as uint64, Boolean and Clock as flags,
 *    String and Binary as heap copies), filled from the start values at
 *    instantiation and fmi3Reset;
 *  - the state machine of FMI 3.0 (Instantiated, Configuration,
 *    Initialization, Event, Continuous-Time, Step, Clock Activation,
 *    Reconfiguration, Terminated); fmi3Set* follows the table of allowed
 *    variables per state, an illegal call returns fmi3Error, is logged, and
 *    leaves the instance unchanged;
 *  - calculated variables are computed by the model's `calculate` before
 *    they are read; time and state events go through the model's `event`;
 *  - Co-Simulation: fmi3DoStep integrates with explicit Euler steps of
 *    MODEL.cs_step, handling time and state events inside the step;
 *  - Scheduled Execution: fmi3ActivateModelPartition runs the model's `tick`;
 *  - optional capabilities the corpus XML does not claim (FMU state,
 *    directional and adjoint derivatives, per-element dependencies, output
 *    derivatives, evaluating discrete states, fractions of clock intervals)
 *    return fmi3Error.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "corpus_model.h"

#ifndef FMU_INSTANTIATION_TOKEN
#error "compile with -DFMU_INSTANTIATION_TOKEN=\"...\" (scenes/build.py does)"
#endif

typedef enum {
    Instantiated = 1 << 0, ConfigurationMode = 1 << 1, InitializationMode = 1 << 2,
    EventMode = 1 << 3, ContinuousTimeMode = 1 << 4, StepMode = 1 << 5,
    ClockActivationMode = 1 << 6, ReconfigurationMode = 1 << 7, Terminated = 1 << 8
} ModelState;

#define INITIALIZED (EventMode | ContinuousTimeMode | StepMode | ClockActivationMode)
#define COMPUTING (InitializationMode | INITIALIZED | Terminated)

typedef enum { POOL_F, POOL_I, POOL_U, POOL_B, POOL_S, POOL_X } Pool;

struct Instance {
    char *name;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback logger;
    int interface;                 /* IF_ME, IF_CS or IF_SE: how it was instantiated */
    fmi3Boolean logging;
    ModelState state;
    double time;
    double next_event;
    fmi3Boolean next_event_defined;
    int dirty;                     /* calculated variables are out of date */
    size_t *offset;                /* per variable: its first element in its pool */
    size_t *cur;                   /* per variable: its current element count */
    double *f;
    fmi3Int64 *i;
    fmi3UInt64 *u;
    fmi3Boolean *b;
    char **s;
    fmi3Byte **x;
    size_t *xsize;
    double *z;                     /* event indicators after the last step (Co-Simulation) */
};

static const char *const CATEGORIES[] = {"logEvents", "logStatusError"};

/* ---------------------------------------------------------------------------------------- */
/* helpers                                                                                   */

static void logf_(Instance *c, fmi3Status status, const char *category, const char *fmt, ...) {
    char buf[512];
    va_list ap;
    if (c == NULL || c->logger == NULL) return;
    if (status < fmi3Error && !c->logging) return;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    c->logger(c->env, status, category, buf);
}

static fmi3Status fail(Instance *c, const char *fn, const char *why) {
    logf_(c, fmi3Error, "logStatusError", "%s: %s", fn, why);
    return fmi3Error;
}

static int allowed(Instance *c, const char *fn, int states) {
    if (c == NULL) return 0;
    if (c->state & states) return 1;
    logf_(c, fmi3Error, "logStatusError", "%s: not allowed in the current state", fn);
    return 0;
}

static Pool pool_of(VarType t) {
    switch (t) {
    case T_FLOAT32: case T_FLOAT64: return POOL_F;
    case T_INT8: case T_INT16: case T_INT32: case T_INT64: case T_ENUMERATION: return POOL_I;
    case T_UINT8: case T_UINT16: case T_UINT32: case T_UINT64: return POOL_U;
    case T_BOOLEAN: case T_CLOCK: return POOL_B;
    case T_STRING: return POOL_S;
    default: return POOL_X;
    }
}

static int find(fmi3ValueReference vr) {
    size_t k;
    for (k = 0; k < MODEL.nvars; k++)
        if (MODEL.vars[k].vr == vr) return (int)k;
    return -1;
}

static int is_state(fmi3ValueReference vr) {
    size_t k;
    for (k = 0; k < MODEL.nx; k++)
        if (MODEL.states[k] == vr) return 1;
    return 0;
}

static char *dup_string(const char *text) {
    size_t n = strlen(text) + 1;
    char *copy = malloc(n);
    if (copy) memcpy(copy, text, n);
    return copy;
}

static int hex_digit(char ch) {
    if (ch >= '0' && ch <= '9') return ch - '0';
    if (ch >= 'a' && ch <= 'f') return ch - 'a' + 10;
    if (ch >= 'A' && ch <= 'F') return ch - 'A' + 10;
    return 0;
}

/* The k-th whitespace-separated token of text (the last one if there are fewer). */
static const char *token(const char *text, size_t k, char *buf, size_t bufsize) {
    const char *p = text, *start = text;
    size_t len = 0, n = 0;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == '\n') p++;
        if (*p == '\0') break;
        start = p;
        while (*p && *p != ' ' && *p != '\t' && *p != '\n') p++;
        len = (size_t)(p - start);
        if (n++ == k) break;
    }
    if (len >= bufsize) len = bufsize - 1;
    memcpy(buf, start, len);
    buf[len] = '\0';
    return buf;
}

static void set_start(Instance *c, size_t k) {
    const VarDef *v = &MODEL.vars[k];
    size_t e, off = c->offset[k];
    char buf[128];
    for (e = 0; e < v->size; e++) {
        const char *tok = v->start && v->type != T_STRING && v->type != T_BINARY
            ? token(v->start, e, buf, sizeof buf) : "0";
        switch (pool_of(v->type)) {
        case POOL_F: c->f[off + e] = strtod(tok, NULL); break;
        case POOL_I: c->i[off + e] = strtoll(tok, NULL, 10); break;
        case POOL_U: c->u[off + e] = strtoull(tok, NULL, 10); break;
        case POOL_B:
            c->b[off + e] = v->type == T_BOOLEAN && (!strcmp(tok, "true") || !strcmp(tok, "1"));
            break;
        case POOL_S:
            free(c->s[off + e]);
            c->s[off + e] = dup_string(v->start ? v->start : "");
            break;
        case POOL_X: {
            const char *hex = v->start ? v->start : "";
            size_t n = strlen(hex) / 2, j;
            free(c->x[off + e]);
            c->x[off + e] = malloc(n ? n : 1);
            for (j = 0; j < n && c->x[off + e]; j++)
                c->x[off + e][j] = (fmi3Byte)(hex_digit(hex[2 * j]) * 16 + hex_digit(hex[2 * j + 1]));
            c->xsize[off + e] = n;
            break;
        }
        }
    }
}

static size_t current_count(Instance *c, size_t k) {
    const VarDef *v = &MODEL.vars[k];
    int s;
    if (v->size_vr == NO_VR) return v->size;
    s = find(v->size_vr);
    if (s < 0) return v->size;
    return (size_t)c->u[c->offset[s]] < v->size ? (size_t)c->u[c->offset[s]] : v->size;
}

static void resize(Instance *c) {
    size_t k;
    for (k = 0; k < MODEL.nvars; k++) c->cur[k] = current_count(c, k);
}

static void apply_start_values(Instance *c) {
    size_t k;
    for (k = 0; k < MODEL.nvars; k++) set_start(c, k);
    resize(c);
    c->time = 0;
    c->next_event_defined = fmi3False;
    c->next_event = 0;
    c->dirty = 1;
}

static void calculate(Instance *c) {
    if (c->dirty && (c->state & COMPUTING)) {
        MODEL.calculate(c);
        c->dirty = 0;
    }
}

/* Whether fmi3Set* may change variable v in the current state (FMI 3.0 §2.3). */
static int may_set(Instance *c, const VarDef *v) {
    if (v->causality == CA_INDEPENDENT || v->variability == VA_CONSTANT || v->type == T_CLOCK)
        return 0;
    switch (c->state) {
    case Instantiated:
        return v->causality != CA_STRUCTURAL_PARAMETER
            && (v->initial == IN_EXACT || v->initial == IN_APPROX);
    case ConfigurationMode:
        return v->causality == CA_STRUCTURAL_PARAMETER;
    case ReconfigurationMode:
        return v->causality == CA_STRUCTURAL_PARAMETER && v->variability == VA_TUNABLE;
    case InitializationMode:
        return v->causality != CA_STRUCTURAL_PARAMETER && v->initial == IN_EXACT;
    case EventMode: case StepMode: case ClockActivationMode:
        return v->causality == CA_INPUT
            || (v->causality == CA_PARAMETER && v->variability == VA_TUNABLE)
            || (c->state == EventMode && c->interface == IF_ME && is_state(v->vr));
    case ContinuousTimeMode:
        return (v->causality == CA_INPUT && v->variability == VA_CONTINUOUS) || is_state(v->vr);
    default:
        return 0;
    }
}

/* A structural parameter that sizes arrays must stay within 1 .. their capacity. */
static int size_ok(const VarDef *v, fmi3UInt64 value) {
    size_t k;
    for (k = 0; k < MODEL.nvars; k++)
        if (MODEL.vars[k].size_vr == v->vr && (value < 1 || value > MODEL.vars[k].size)) return 0;
    return 1;
}

static int type_matches(VarType have, VarType want) {
    return have == want || (want == T_INT64 && have == T_ENUMERATION);
}

/* Check a get or set of nvr variables of one type holding nValues elements in total. */
static int lookup(Instance *c, const char *fn, const fmi3ValueReference vrs[], size_t nvr,
                  VarType type, size_t nValues, int setting) {
    size_t j, total = 0;
    for (j = 0; j < nvr; j++) {
        int k = find(vrs[j]);
        if (k < 0 || !type_matches(MODEL.vars[k].type, type)) {
            logf_(c, fmi3Error, "logStatusError", "%s: no variable of this type with "
                  "valueReference %u", fn, (unsigned)vrs[j]);
            return 0;
        }
        if (setting && !may_set(c, &MODEL.vars[k])) {
            logf_(c, fmi3Error, "logStatusError", "%s: variable '%s' cannot be set in the "
                  "current state", fn, MODEL.vars[k].name);
            return 0;
        }
        total += c->cur[k];
    }
    if (total != nValues) {
        logf_(c, fmi3Error, "logStatusError", "%s: nValues is %u, expected %u", fn,
              (unsigned)nValues, (unsigned)total);
        return 0;
    }
    return 1;
}

static int may_get(Instance *c, const char *fn) {
    return allowed(c, fn, Instantiated | COMPUTING);
}

/* ---------------------------------------------------------------------------------------- */
/* the model's side                                                                          */

static size_t slot(Instance *c, fmi3ValueReference vr) {
    int k = find(vr);
    return k < 0 ? 0 : c->offset[k];
}

double *f64(Instance *c, fmi3ValueReference vr) { return &c->f[slot(c, vr)]; }
fmi3Int64 *i64(Instance *c, fmi3ValueReference vr) { return &c->i[slot(c, vr)]; }
fmi3UInt64 *u64(Instance *c, fmi3ValueReference vr) { return &c->u[slot(c, vr)]; }
fmi3Boolean *flag(Instance *c, fmi3ValueReference vr) { return &c->b[slot(c, vr)]; }
const char *string_value(Instance *c, fmi3ValueReference vr) { return c->s[slot(c, vr)]; }

const fmi3Byte *binary_value(Instance *c, fmi3ValueReference vr, size_t *size) {
    *size = c->xsize[slot(c, vr)];
    return c->x[slot(c, vr)];
}

fmi3Status set_string(Instance *c, fmi3ValueReference vr, const char *value) {
    char *copy = dup_string(value);
    if (copy == NULL) return fmi3Error;
    free(c->s[slot(c, vr)]);
    c->s[slot(c, vr)] = copy;
    return fmi3OK;
}

size_t count(Instance *c, fmi3ValueReference vr) {
    int k = find(vr);
    return k < 0 ? 0 : c->cur[k];
}

double fmu_time(Instance *c) { return c->time; }

void set_next_event_time(Instance *c, double t) {
    c->next_event = t;
    c->next_event_defined = fmi3True;
}

fmi3Boolean next_event_time(Instance *c, double *t) {
    *t = c->next_event;
    return c->next_event_defined;
}

void clear_next_event_time(Instance *c) { c->next_event_defined = fmi3False; }

void tick_output_clock(Instance *c, fmi3ValueReference clock) { *flag(c, clock) = fmi3True; }

void log_event(Instance *c, const char *message) {
    logf_(c, fmi3OK, "logEvents", "t=%g: %s", c->time, message);
}

/* Run the event function: discrete updates, state reinitialisation, next time event. */
static fmi3Boolean handle_event(Instance *c) {
    fmi3Boolean changed = fmi3False;
    calculate(c);
    if (MODEL.event) MODEL.event(c, &changed);
    c->dirty = 1;
    calculate(c);
    return changed;
}

/* ---------------------------------------------------------------------------------------- */
/* inquiry, logging, instances                                                               */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn,
                               size_t nCategories, const fmi3String categories[]) {
    Instance *c = (Instance *)instance;
    size_t j, k;
    if (c == NULL) return fmi3Error;
    for (j = 0; j < nCategories; j++) {
        int known = 0;
        for (k = 0; k < sizeof CATEGORIES / sizeof CATEGORIES[0]; k++)
            if (categories[j] && !strcmp(categories[j], CATEGORIES[k])) known = 1;
        if (!known) return fail(c, "fmi3SetDebugLogging", "unknown log category");
    }
    c->logging = loggingOn;
    return fmi3OK;
}

static fmi3Instance instantiate(int interface, fmi3String name, fmi3String token,
                                fmi3Boolean loggingOn, fmi3InstanceEnvironment env,
                                fmi3LogMessageCallback logger) {
    Instance *c;
    size_t k, sizes[6] = {0, 0, 0, 0, 0, 0}, total;
    if (!(MODEL.interfaces & interface)) return NULL;
    if (token == NULL || strcmp(token, FMU_INSTANTIATION_TOKEN) != 0) {
        if (logger) logger(env, fmi3Error, "logStatusError", "wrong instantiationToken");
        return NULL;
    }
    c = calloc(1, sizeof *c);
    if (c == NULL) return NULL;
    c->name = dup_string(name ? name : "");
    c->env = env;
    c->logger = logger;
    c->logging = loggingOn;
    c->interface = interface;
    c->state = Instantiated;
    c->offset = calloc(MODEL.nvars + 1, sizeof *c->offset);
    c->cur = calloc(MODEL.nvars + 1, sizeof *c->cur);
    for (k = 0; k < MODEL.nvars && c->offset; k++) {
        Pool p = pool_of(MODEL.vars[k].type);
        c->offset[k] = sizes[p];
        sizes[p] += MODEL.vars[k].size;
    }
    total = 1;
    c->f = calloc(sizes[POOL_F] + total, sizeof *c->f);
    c->i = calloc(sizes[POOL_I] + total, sizeof *c->i);
    c->u = calloc(sizes[POOL_U] + total, sizeof *c->u);
    c->b = calloc(sizes[POOL_B] + total, sizeof *c->b);
    c->s = calloc(sizes[POOL_S] + total, sizeof *c->s);
    c->x = calloc(sizes[POOL_X] + total, sizeof *c->x);
    c->xsize = calloc(sizes[POOL_X] + total, sizeof *c->xsize);
    c->z = calloc(MODEL.nz + 1, sizeof *c->z);
    if (!c->name || !c->offset || !c->cur || !c->f || !c->i || !c->u || !c->b || !c->s
            || !c->x || !c->xsize || !c->z) {
        fmi3FreeInstance(c);
        return NULL;
    }
    apply_start_values(c);
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)resourcePath; (void)visible;
    return instantiate(IF_ME, instanceName, instantiationToken, loggingOn, instanceEnvironment,
                       logMessage);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible,
                                         fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
                                         fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    /* hasEventMode, providesIntermediateUpdate and mightReturnEarlyFromDoStep are false:
     * the FMU handles its events inside fmi3DoStep and never returns early. */
    (void)resourcePath; (void)visible; (void)eventModeUsed; (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables; (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    return instantiate(IF_CS, instanceName, instantiationToken, loggingOn, instanceEnvironment,
                       logMessage);
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName,
                                               fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)resourcePath; (void)visible; (void)clockUpdate; (void)lockPreemption;
    (void)unlockPreemption;
    return instantiate(IF_SE, instanceName, instantiationToken, loggingOn, instanceEnvironment,
                       logMessage);
}

void fmi3FreeInstance(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    size_t k, e;
    if (c == NULL) return;
    for (k = 0; k < MODEL.nvars && c->offset; k++) {
        Pool p = pool_of(MODEL.vars[k].type);
        for (e = 0; e < MODEL.vars[k].size; e++) {
            if (p == POOL_S && c->s) free(c->s[c->offset[k] + e]);
            if (p == POOL_X && c->x) free(c->x[c->offset[k] + e]);
        }
    }
    free(c->name); free(c->offset); free(c->cur); free(c->f); free(c->i); free(c->u);
    free(c->b); free(c->s); free(c->x); free(c->xsize); free(c->z);
    free(c);
}

/* ---------------------------------------------------------------------------------------- */
/* modes                                                                                     */

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    Instance *c = (Instance *)instance;
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    if (!allowed(c, "fmi3EnterInitializationMode", Instantiated)) return fmi3Error;
    c->time = startTime;
    c->state = InitializationMode;
    c->dirty = 1;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (!allowed(c, "fmi3ExitInitializationMode", InitializationMode)) return fmi3Error;
    c->state = c->interface == IF_ME ? EventMode
             : c->interface == IF_CS ? StepMode : ClockActivationMode;
    handle_event(c);
    if (MODEL.nz) MODEL.event_indicators(c, c->z);
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (!allowed(c, "fmi3EnterEventMode", ContinuousTimeMode)) return fmi3Error;
    c->state = EventMode;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (!allowed(c, "fmi3Terminate", INITIALIZED)) return fmi3Error;
    calculate(c);
    c->state = Terminated;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (c == NULL) return fmi3Error;
    c->state = Instantiated;
    apply_start_values(c);
    return fmi3OK;
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    size_t k;
    int structural = 0, tunable = 0;
    if (!allowed(c, "fmi3EnterConfigurationMode", Instantiated | EventMode | StepMode
                 | ClockActivationMode)) return fmi3Error;
    for (k = 0; k < MODEL.nvars; k++) {
        if (MODEL.vars[k].causality != CA_STRUCTURAL_PARAMETER) continue;
        structural = 1;
        if (MODEL.vars[k].variability == VA_TUNABLE) tunable = 1;
    }
    if (c->state == Instantiated) {
        if (!structural) return fail(c, "fmi3EnterConfigurationMode", "no structural parameter");
        c->state = ConfigurationMode;
    } else {
        if (!tunable)
            return fail(c, "fmi3EnterConfigurationMode", "no tunable structural parameter");
        c->state = ReconfigurationMode;
    }
    return fmi3OK;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    size_t k;
    if (!allowed(c, "fmi3ExitConfigurationMode", ConfigurationMode | ReconfigurationMode))
        return fmi3Error;
    for (k = 0; k < MODEL.nvars; k++) {
        size_t n = current_count(c, k);
        if (n != c->cur[k]) {          /* a resized array starts again from its start value */
            set_start(c, k);
            c->cur[k] = n;
        }
    }
    if (c->state == ConfigurationMode) {
        c->state = Instantiated;
    } else {
        c->state = c->interface == IF_ME ? EventMode
                 : c->interface == IF_CS ? StepMode : ClockActivationMode;
    }
    c->dirty = 1;
    return fmi3OK;
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    return fail((Instance *)instance, "fmi3EvaluateDiscreteStates",
                "not provided (providesEvaluateDiscreteStates is false)");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    Instance *c = (Instance *)instance;
    fmi3Boolean changed;
    size_t k;
    if (!allowed(c, "fmi3UpdateDiscreteStates", EventMode)) return fmi3Error;
    for (k = 0; k < MODEL.nvars; k++) {           /* input Clocks the importer set active */
        const VarDef *v = &MODEL.vars[k];
        if (v->type == T_CLOCK && v->causality == CA_INPUT && c->b[c->offset[k]]) {
            calculate(c);
            if (MODEL.tick) MODEL.tick(c, v->vr);
            c->b[c->offset[k]] = fmi3False;
            c->dirty = 1;
        }
    }
    changed = handle_event(c);
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = changed;
    if (nextEventTimeDefined) *nextEventTimeDefined = c->next_event_defined;
    if (nextEventTime) *nextEventTime = c->next_event_defined ? c->next_event : 0.0;
    return fmi3OK;
}

/* ---------------------------------------------------------------------------------------- */
/* getting and setting values                                                                */

#define GET_NUMBERS(FN, CTYPE, VT, POOLVAR)                                                    \
    fmi3Status FN(fmi3Instance instance, const fmi3ValueReference valueReferences[],           \
                  size_t nValueReferences, CTYPE values[], size_t nValues) {                   \
        Instance *c = (Instance *)instance;                                                    \
        size_t j, e, n = 0;                                                                    \
        if (!may_get(c, #FN)) return fmi3Error;                                                \
        if (!lookup(c, #FN, valueReferences, nValueReferences, VT, nValues, 0))                \
            return fmi3Error;                                                                  \
        calculate(c);                                                                          \
        for (j = 0; j < nValueReferences; j++) {                                               \
            int k = find(valueReferences[j]);                                                  \
            for (e = 0; e < c->cur[k]; e++) values[n++] = (CTYPE)c->POOLVAR[c->offset[k] + e]; \
        }                                                                                      \
        return fmi3OK;                                                                         \
    }

#define SET_NUMBERS(FN, CTYPE, VT, POOLVAR, STORE)                                             \
    fmi3Status FN(fmi3Instance instance, const fmi3ValueReference valueReferences[],           \
                  size_t nValueReferences, const CTYPE values[], size_t nValues) {             \
        Instance *c = (Instance *)instance;                                                    \
        size_t j, e, n = 0;                                                                    \
        if (c == NULL) return fmi3Error;                                                       \
        if (!lookup(c, #FN, valueReferences, nValueReferences, VT, nValues, 1))                \
            return fmi3Error;                                                                  \
        for (j = 0; j < nValueReferences; j++) {                                               \
            const VarDef *v = &MODEL.vars[find(valueReferences[j])];                           \
            if (v->causality == CA_STRUCTURAL_PARAMETER && VT == T_UINT64                      \
                    && !size_ok(v, (fmi3UInt64)values[n]))                                     \
                return fail(c, #FN, "array size out of range");                                \
            n += c->cur[find(valueReferences[j])];                                             \
        }                                                                                      \
        n = 0;                                                                                 \
        for (j = 0; j < nValueReferences; j++) {                                               \
            int k = find(valueReferences[j]);                                                  \
            for (e = 0; e < c->cur[k]; e++) c->POOLVAR[c->offset[k] + e] = (STORE)values[n++]; \
        }                                                                                      \
        c->dirty = 1;                                                                          \
        return fmi3OK;                                                                         \
    }

GET_NUMBERS(fmi3GetFloat32, fmi3Float32, T_FLOAT32, f)
GET_NUMBERS(fmi3GetFloat64, fmi3Float64, T_FLOAT64, f)
GET_NUMBERS(fmi3GetInt8, fmi3Int8, T_INT8, i)
GET_NUMBERS(fmi3GetUInt8, fmi3UInt8, T_UINT8, u)
GET_NUMBERS(fmi3GetInt16, fmi3Int16, T_INT16, i)
GET_NUMBERS(fmi3GetUInt16, fmi3UInt16, T_UINT16, u)
GET_NUMBERS(fmi3GetInt32, fmi3Int32, T_INT32, i)
GET_NUMBERS(fmi3GetUInt32, fmi3UInt32, T_UINT32, u)
GET_NUMBERS(fmi3GetInt64, fmi3Int64, T_INT64, i)
GET_NUMBERS(fmi3GetUInt64, fmi3UInt64, T_UINT64, u)
GET_NUMBERS(fmi3GetBoolean, fmi3Boolean, T_BOOLEAN, b)

SET_NUMBERS(fmi3SetFloat32, fmi3Float32, T_FLOAT32, f, double)
SET_NUMBERS(fmi3SetFloat64, fmi3Float64, T_FLOAT64, f, double)
SET_NUMBERS(fmi3SetInt8, fmi3Int8, T_INT8, i, fmi3Int64)
SET_NUMBERS(fmi3SetUInt8, fmi3UInt8, T_UINT8, u, fmi3UInt64)
SET_NUMBERS(fmi3SetInt16, fmi3Int16, T_INT16, i, fmi3Int64)
SET_NUMBERS(fmi3SetUInt16, fmi3UInt16, T_UINT16, u, fmi3UInt64)
SET_NUMBERS(fmi3SetInt32, fmi3Int32, T_INT32, i, fmi3Int64)
SET_NUMBERS(fmi3SetUInt32, fmi3UInt32, T_UINT32, u, fmi3UInt64)
SET_NUMBERS(fmi3SetInt64, fmi3Int64, T_INT64, i, fmi3Int64)
SET_NUMBERS(fmi3SetUInt64, fmi3UInt64, T_UINT64, u, fmi3UInt64)
SET_NUMBERS(fmi3SetBoolean, fmi3Boolean, T_BOOLEAN, b, fmi3Boolean)

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, fmi3String values[], size_t nValues) {
    Instance *c = (Instance *)instance;
    size_t j, e, n = 0;
    if (!may_get(c, "fmi3GetString")) return fmi3Error;
    if (!lookup(c, "fmi3GetString", valueReferences, nValueReferences, T_STRING, nValues, 0))
        return fmi3Error;
    calculate(c);
    for (j = 0; j < nValueReferences; j++) {
        int k = find(valueReferences[j]);
        for (e = 0; e < c->cur[k]; e++) values[n++] = c->s[c->offset[k] + e];
    }
    return fmi3OK;
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const fmi3String values[], size_t nValues) {
    Instance *c = (Instance *)instance;
    size_t j, e, n = 0;
    if (c == NULL) return fmi3Error;
    if (!lookup(c, "fmi3SetString", valueReferences, nValueReferences, T_STRING, nValues, 1))
        return fmi3Error;
    for (j = 0; j < nValues; j++)
        if (values[j] == NULL) return fail(c, "fmi3SetString", "a value is NULL");
    for (j = 0; j < nValueReferences; j++) {
        int k = find(valueReferences[j]);
        for (e = 0; e < c->cur[k]; e++, n++) {
            char *copy = dup_string(values[n]);
            if (copy == NULL) return fail(c, "fmi3SetString", "out of memory");
            free(c->s[c->offset[k] + e]);
            c->s[c->offset[k] + e] = copy;
        }
    }
    c->dirty = 1;
    return fmi3OK;
}

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[],
                         size_t nValues) {
    Instance *c = (Instance *)instance;
    size_t j, e, n = 0;
    if (!may_get(c, "fmi3GetBinary")) return fmi3Error;
    if (!lookup(c, "fmi3GetBinary", valueReferences, nValueReferences, T_BINARY, nValues, 0))
        return fmi3Error;
    calculate(c);
    for (j = 0; j < nValueReferences; j++) {
        int k = find(valueReferences[j]);
        for (e = 0; e < c->cur[k]; e++, n++) {
            valueSizes[n] = c->xsize[c->offset[k] + e];
            values[n] = c->x[c->offset[k] + e];
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues) {
    Instance *c = (Instance *)instance;
    size_t j, e, n = 0;
    if (c == NULL) return fmi3Error;
    if (!lookup(c, "fmi3SetBinary", valueReferences, nValueReferences, T_BINARY, nValues, 1))
        return fmi3Error;
    for (j = 0; j < nValues; j++)
        if (values[j] == NULL && valueSizes[j] > 0)
            return fail(c, "fmi3SetBinary", "a value is NULL");
    for (j = 0; j < nValueReferences; j++) {
        int k = find(valueReferences[j]);
        for (e = 0; e < c->cur[k]; e++, n++) {
            fmi3Byte *copy = malloc(valueSizes[n] ? valueSizes[n] : 1);
            if (copy == NULL) return fail(c, "fmi3SetBinary", "out of memory");
            if (valueSizes[n]) memcpy(copy, values[n], valueSizes[n]);
            free(c->x[c->offset[k] + e]);
            c->x[c->offset[k] + e] = copy;
            c->xsize[c->offset[k] + e] = valueSizes[n];
        }
    }
    c->dirty = 1;
    return fmi3OK;
}

/* ---------------------------------------------------------------------------------------- */
/* clocks                                                                                    */

static int find_clock(Instance *c, const char *fn, fmi3ValueReference vr, int input_only) {
    int k = find(vr);
    if (k < 0 || MODEL.vars[k].type != T_CLOCK
            || (input_only && MODEL.vars[k].causality != CA_INPUT)) {
        logf_(c, fmi3Error, "logStatusError", "%s: valueReference %u is not %s Clock", fn,
              (unsigned)vr, input_only ? "an input" : "a");
        return -1;
    }
    return k;
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[]) {
    Instance *c = (Instance *)instance;
    size_t j;
    if (!allowed(c, "fmi3GetClock", EventMode | ClockActivationMode | StepMode)) return fmi3Error;
    for (j = 0; j < nValueReferences; j++)
        if (find_clock(c, "fmi3GetClock", valueReferences[j], 0) < 0) return fmi3Error;
    for (j = 0; j < nValueReferences; j++) {
        int k = find(valueReferences[j]);
        values[j] = c->b[c->offset[k]];
        if (MODEL.vars[k].causality == CA_OUTPUT) c->b[c->offset[k]] = fmi3False;  /* read */
    }
    return fmi3OK;
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[]) {
    Instance *c = (Instance *)instance;
    size_t j;
    if (!allowed(c, "fmi3SetClock", EventMode)) return fmi3Error;
    for (j = 0; j < nValueReferences; j++)
        if (find_clock(c, "fmi3SetClock", valueReferences[j], 1) < 0) return fmi3Error;
    for (j = 0; j < nValueReferences; j++)
        c->b[c->offset[find(valueReferences[j])]] = values[j];
    return fmi3OK;
}

/* A Clock's VarDef.start holds its intervalDecimal; NULL: aperiodic (no interval to get). */
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    Instance *c = (Instance *)instance;
    size_t j;
    if (!allowed(c, "fmi3GetIntervalDecimal", INITIALIZED | InitializationMode)) return fmi3Error;
    for (j = 0; j < nValueReferences; j++) {
        int k = find_clock(c, "fmi3GetIntervalDecimal", valueReferences[j], 0);
        if (k < 0) return fmi3Error;
        if (MODEL.vars[k].start == NULL)
            return fail(c, "fmi3GetIntervalDecimal", "the Clock has no interval");
    }
    for (j = 0; j < nValueReferences; j++) {
        intervals[j] = strtod(MODEL.vars[find(valueReferences[j])].start, NULL);
        qualifiers[j] = fmi3IntervalUnchanged;
    }
    return fmi3OK;
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) {
    Instance *c = (Instance *)instance;
    size_t j;
    if (!allowed(c, "fmi3GetShiftDecimal", INITIALIZED | InitializationMode)) return fmi3Error;
    for (j = 0; j < nValueReferences; j++)
        if (find_clock(c, "fmi3GetShiftDecimal", valueReferences[j], 0) < 0) return fmi3Error;
    for (j = 0; j < nValueReferences; j++) shifts[j] = 0.0;
    return fmi3OK;
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[],
                                   fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    (void)qualifiers;
    return fail((Instance *)instance, "fmi3GetIntervalFraction", "supportsFraction is false");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[],
                                fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return fail((Instance *)instance, "fmi3GetShiftFraction", "supportsFraction is false");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    (void)valueReferences; (void)nValueReferences; (void)intervals;
    return fail((Instance *)instance, "fmi3SetIntervalDecimal",
                "no Clock has a tunable, changing or countdown interval");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return fail((Instance *)instance, "fmi3SetIntervalFraction", "supportsFraction is false");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) {
    (void)valueReferences; (void)nValueReferences; (void)shifts;
    return fail((Instance *)instance, "fmi3SetShiftDecimal", "no Clock has a settable shift");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions;
    return fail((Instance *)instance, "fmi3SetShiftFraction", "supportsFraction is false");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    Instance *c = (Instance *)instance;
    if (!allowed(c, "fmi3ActivateModelPartition", ClockActivationMode)) return fmi3Error;
    if (find_clock(c, "fmi3ActivateModelPartition", clockReference, 1) < 0) return fmi3Error;
    if (activationTime < c->time) return fail(c, "fmi3ActivateModelPartition", "time went back");
    c->time = activationTime;
    c->dirty = 1;
    calculate(c);
    if (MODEL.tick) MODEL.tick(c, clockReference);
    c->dirty = 1;
    calculate(c);
    return fmi3OK;
}

/* ---------------------------------------------------------------------------------------- */
/* capabilities the corpus does not claim                                                    */

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference; (void)nDependencies;
    return fail((Instance *)instance, "fmi3GetNumberOfVariableDependencies",
                "providesPerElementDependencies is false");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)dependent; (void)elementIndicesOfDependent; (void)independents;
    (void)elementIndicesOfIndependents; (void)dependencyKinds; (void)nDependencies;
    return fail((Instance *)instance, "fmi3GetVariableDependencies",
                "providesPerElementDependencies is false");
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    (void)FMUState;
    return fail((Instance *)instance, "fmi3GetFMUState", "canGetAndSetFMUState is false");
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    (void)FMUState;
    return fail((Instance *)instance, "fmi3SetFMUState", "canGetAndSetFMUState is false");
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    (void)FMUState;
    return fail((Instance *)instance, "fmi3FreeFMUState", "canGetAndSetFMUState is false");
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    (void)FMUState; (void)size;
    return fail((Instance *)instance, "fmi3SerializedFMUStateSize", "canSerializeFMUState is false");
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size) {
    (void)FMUState; (void)serializedState; (void)size;
    return fail((Instance *)instance, "fmi3SerializeFMUState", "canSerializeFMUState is false");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState) {
    (void)serializedState; (void)size; (void)FMUState;
    return fail((Instance *)instance, "fmi3DeserializeFMUState", "canSerializeFMUState is false");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;
    (void)sensitivity; (void)nSensitivity;
    return fail((Instance *)instance, "fmi3GetDirectionalDerivative",
                "providesDirectionalDerivatives is false");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed;
    (void)sensitivity; (void)nSensitivity;
    return fail((Instance *)instance, "fmi3GetAdjointDerivative",
                "providesAdjointDerivatives is false");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t nValues) {
    (void)valueReferences; (void)nValueReferences; (void)orders; (void)values; (void)nValues;
    return fail((Instance *)instance, "fmi3GetOutputDerivatives",
                "maxOutputDerivativeOrder is 0");
}

/* ---------------------------------------------------------------------------------------- */
/* Model Exchange                                                                            */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (!allowed(c, "fmi3EnterContinuousTimeMode", EventMode) || c->interface != IF_ME)
        return fmi3Error;
    c->state = ContinuousTimeMode;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation) {
    Instance *c = (Instance *)instance;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(c, "fmi3CompletedIntegratorStep", ContinuousTimeMode)) return fmi3Error;
    if (enterEventMode) *enterEventMode = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    Instance *c = (Instance *)instance;
    if (!allowed(c, "fmi3SetTime", EventMode | ContinuousTimeMode) || c->interface != IF_ME)
        return fmi3Error;
    c->time = time;
    c->dirty = 1;
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    Instance *c = (Instance *)instance;
    size_t k;
    if (!allowed(c, "fmi3SetContinuousStates", EventMode | ContinuousTimeMode)) return fmi3Error;
    if (nContinuousStates != MODEL.nx)
        return fail(c, "fmi3SetContinuousStates", "wrong nContinuousStates");
    for (k = 0; k < MODEL.nx; k++) *f64(c, MODEL.states[k]) = continuousStates[k];
    c->dirty = 1;
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    Instance *c = (Instance *)instance;
    size_t k;
    if (!allowed(c, "fmi3GetContinuousStateDerivatives", COMPUTING)) return fmi3Error;
    if (nContinuousStates != MODEL.nx)
        return fail(c, "fmi3GetContinuousStateDerivatives", "wrong nContinuousStates");
    calculate(c);
    for (k = 0; k < MODEL.nx; k++) derivatives[k] = *f64(c, MODEL.derivatives[k]);
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) {
    Instance *c = (Instance *)instance;
    if (!allowed(c, "fmi3GetEventIndicators", COMPUTING)) return fmi3Error;
    if (nEventIndicators != MODEL.nz)
        return fail(c, "fmi3GetEventIndicators", "wrong nEventIndicators");
    calculate(c);
    if (MODEL.nz) MODEL.event_indicators(c, eventIndicators);
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    Instance *c = (Instance *)instance;
    size_t k;
    if (!allowed(c, "fmi3GetContinuousStates", Instantiated | COMPUTING)) return fmi3Error;
    if (nContinuousStates != MODEL.nx)
        return fail(c, "fmi3GetContinuousStates", "wrong nContinuousStates");
    for (k = 0; k < MODEL.nx; k++) continuousStates[k] = *f64(c, MODEL.states[k]);
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    Instance *c = (Instance *)instance;
    size_t k;
    if (!allowed(c, "fmi3GetNominalsOfContinuousStates", Instantiated | COMPUTING))
        return fmi3Error;
    if (nContinuousStates != MODEL.nx)
        return fail(c, "fmi3GetNominalsOfContinuousStates", "wrong nContinuousStates");
    for (k = 0; k < MODEL.nx; k++) nominals[k] = 1.0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    Instance *c = (Instance *)instance;
    if (c == NULL || nEventIndicators == NULL) return fmi3Error;
    *nEventIndicators = MODEL.nz;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    Instance *c = (Instance *)instance;
    if (c == NULL || nContinuousStates == NULL) return fmi3Error;
    *nContinuousStates = MODEL.nx;
    return fmi3OK;
}

/* ---------------------------------------------------------------------------------------- */
/* Co-Simulation                                                                             */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    /* hasEventMode is false: the instance never is in Event Mode as a Co-Simulation FMU. */
    return fail((Instance *)instance, "fmi3EnterStepMode", "hasEventMode is false");
}

static int crossed(Instance *c) {
    double z[16];
    size_t k;
    int any = 0;
    if (MODEL.nz == 0 || MODEL.nz > 16) return 0;
    calculate(c);
    MODEL.event_indicators(c, z);
    for (k = 0; k < MODEL.nz; k++) {
        if ((c->z[k] > 0) != (z[k] > 0)) any = 1;
        c->z[k] = z[k];
    }
    return any;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    Instance *c = (Instance *)instance;
    double target, eps;
    size_t k;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(c, "fmi3DoStep", StepMode)) return fmi3Error;
    eps = 1e-9 * (1.0 + fabs(c->time));
    if (fabs(currentCommunicationPoint - c->time) > eps)
        return fail(c, "fmi3DoStep", "currentCommunicationPoint is not the FMU's time");
    if (communicationStepSize < 0) return fail(c, "fmi3DoStep", "negative communicationStepSize");
    target = currentCommunicationPoint + communicationStepSize;
    while (c->time < target - eps) {
        double h = target - c->time < MODEL.cs_step ? target - c->time : MODEL.cs_step;
        if (c->next_event_defined && c->next_event > c->time && c->next_event < c->time + h)
            h = c->next_event - c->time;
        calculate(c);
        for (k = 0; k < MODEL.nx; k++)
            *f64(c, MODEL.states[k]) += h * *f64(c, MODEL.derivatives[k]);
        c->time += h;
        c->dirty = 1;
        if (crossed(c) || (c->next_event_defined && c->time >= c->next_event - eps)) {
            handle_event(c);
            crossed(c);
        }
    }
    c->time = target;
    c->dirty = 1;
    calculate(c);
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (earlyReturn) *earlyReturn = fmi3False;
    if (lastSuccessfulTime) *lastSuccessfulTime = c->time;
    return fmi3OK;
}
