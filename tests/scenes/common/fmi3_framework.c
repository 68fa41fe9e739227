/*
 * fmi3_framework.c - a small FMI 3.0 Model Exchange implementation for the
 * lsdae test scenes.  One model file supplies `const ModelDef MODEL`
 * (see dae_model.h); this file provides every function of fmi3Functions.h.
 *
 * ODE mode (enable parameter false, the default): the FMU solves g = 0 for the
 * algebraic variables w itself (Newton, analytic dg/dw, warm start) whenever
 * t, x or u changed; partial derivatives are total derivatives.
 * DAE mode (enable parameter true): w is set by the importer in
 * Initialization (as a guess), Event and Continuous-Time Mode and never
 * overwritten after initialisation; residuals are readable; partial
 * derivatives are the partials with w as a known and residuals as unknowns.
 * Initialization Mode solves g = 0 in both modes (w are initial unknowns).
 *
 * Illegal calls return fmi3Error and leave the instance unchanged.
 *
 * Defect variants for the probe tests (tests/probes/defects_basic.py), each
 * compiled in only with its -DDEFECT_... macro:
 *   DEFECT_SEGFAULT_GETFLOAT64     fmi3GetFloat64 of a residual crashes (Continuous-Time Mode)
 *   DEFECT_HANG_DIRECTIONAL        fmi3GetDirectionalDerivative never returns
 *   DEFECT_MEMORY_BLOWUP           fmi3GetContinuousStateDerivatives allocates until it aborts
 *   DEFECT_EXIT_IN_CALL            fmi3SetTime calls exit() once time has advanced
 *   DEFECT_INCONSISTENT_INIT       DAE mode: w is reset to its guess when initialisation ends
 *   DEFECT_NO_RECONFIGURATION      Reconfiguration Mode refused although the switch is tunable
 *   DEFECT_ODE_DERIVATIVES_FAIL    ODE mode: fmi3GetContinuousStateDerivatives returns fmi3Error
 *   DEFECT_DAE_INIT_REFUSED        DAE mode: fmi3ExitInitializationMode returns fmi3Error
 *   DEFECT_W_NOT_SETTABLE          DAE mode: w cannot be set in Continuous-Time Mode
 *   DEFECT_EVAL_ERROR_AFTER_START  DAE mode: reading residuals fails once time has advanced
 *   DEFECT_MISSING_EXPORT          fmi3GetClock is not exported
 *   DEFECT_DAE_ONLY                always in DAE mode, as if the switch were stuck at true
 *   DEFECT_FATAL_DIRECTIONAL       fmi3GetDirectionalDerivative returns fmi3Fatal
 *   DEFECT_WRONG_ADJOINT           the adjoint alone doubles d(res[0])/d(w[0]) (DAE mode)
 *   DEFECT_ODE_DAE_INCONSISTENT    ODE mode solves g = 0.05 instead of g = 0
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dae_model.h"

#ifndef FMU_INSTANTIATION_TOKEN
#error "compile with -DFMU_INSTANTIATION_TOKEN=\"...\" (tests/scenes/build.py does)"
#endif

#define NMAX      FMU_MAX_VARS
#define NX        MODEL.nx
#define NW        MODEL.nw
#define NU        MODEL.nu
#define NY        MODEL.ny
#define NCOLS     (NX + NW + NU + 1)      /* columns x, w, u, t */
#define EROWS_MAX (4 * NMAX)              /* rows der, res, y (and w) */
#define ECOLS_MAX (3 * NMAX + 1)

typedef enum {
    Instantiated        = 1 << 0,
    ConfigurationMode   = 1 << 1,
    InitializationMode  = 1 << 2,
    EventMode           = 1 << 3,
    ContinuousTimeMode  = 1 << 4,
    ReconfigurationMode = 1 << 5,
    Terminated          = 1 << 6
} ModelState;

#define ANY_STATE   0x7F
#define RUNNING     (InitializationMode | EventMode | ContinuousTimeMode | Terminated)
#define NOT_CONFIG  (ANY_STATE & ~(ConfigurationMode | ReconfigurationMode))

/* Everything that fmi3GetFMUState saves. */
typedef struct {
    ModelState  state;
    fmi3Boolean dae;
    double t;
    double x[NMAX], w[NMAX], u[NMAX];
    double der[NMAX], res[NMAX], y[NMAX];
    int w_consistent;  /* w solves g = 0 for the current (t, x, u) */
    int eval_valid;    /* der, res, y are up to date */
} Data;

typedef struct {
    Data d;
    char *name;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback  logger;
    fmi3Boolean logging;
} Instance;

enum { K_NONE, K_TIME, K_ENABLE, K_X, K_DER, K_W, K_RES, K_U, K_Y };

/* ------------------------------------------------------------------ helpers */

static const char *state_name(ModelState s) {
    switch (s) {
    case Instantiated:        return "Instantiated";
    case ConfigurationMode:   return "Configuration Mode";
    case InitializationMode:  return "Initialization Mode";
    case EventMode:           return "Event Mode";
    case ContinuousTimeMode:  return "Continuous-Time Mode";
    case ReconfigurationMode: return "Reconfiguration Mode";
    default:                  return "Terminated";
    }
}

static void logmsg(Instance *c, fmi3Status status, const char *fmt, ...) {
    char buf[512];
    va_list ap;
    if (!c || !c->logger || (status < fmi3Error && !c->logging)) return;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    c->logger(c->env, status, status >= fmi3Error ? "logStatusError" : "logEvents", buf);
}

#define FAIL(...) do { logmsg(c, fmi3Error, __VA_ARGS__); return fmi3Error; } while (0)

/* Declares `c`, checks the instance pointer and the state mask. */
#define BEGIN(fn, mask)                                                        \
    Instance *c = (Instance *)instance;                                        \
    if (!c) return fmi3Error;                                                  \
    if (!(c->d.state & (mask)))                                                \
        FAIL("%s: not allowed in %s", fn, state_name(c->d.state))

static int lookup(fmi3ValueReference vr, int *idx) {
    int i;
    *idx = 0;
    if (vr == MODEL.vr_time) return K_TIME;
    if (vr == MODEL.vr_enable) return K_ENABLE;
    for (i = 0; i < NX; i++) {
        *idx = i;
        if (vr == MODEL.vr_x[i]) return K_X;
        if (vr == MODEL.vr_der[i]) return K_DER;
    }
    for (i = 0; i < NW; i++) {
        *idx = i;
        if (vr == MODEL.vr_w[i]) return K_W;
        if (vr == MODEL.vr_res[i]) return K_RES;
    }
    for (i = 0; i < NU; i++) { *idx = i; if (vr == MODEL.vr_u[i]) return K_U; }
    for (i = 0; i < NY; i++) { *idx = i; if (vr == MODEL.vr_y[i]) return K_Y; }
    return K_NONE;
}

static double *slot(Data *d, int kind, int i) {
    switch (kind) {
    case K_TIME: return &d->t;
    case K_X:    return &d->x[i];
    case K_DER:  return &d->der[i];
    case K_W:    return &d->w[i];
    case K_RES:  return &d->res[i];
    case K_U:    return &d->u[i];
    case K_Y:    return &d->y[i];
    default:     return NULL;
    }
}

static void reset_data(Data *d) {
    memset(d, 0, sizeof *d);
    d->state = Instantiated;
#ifdef DEFECT_DAE_ONLY
    d->dae = fmi3True;   /* a "DAE-only" FMU of the first exporter releases */
#else
    d->dae = fmi3False;
#endif
    memcpy(d->x, MODEL.x_start, sizeof d->x);
    memcpy(d->w, MODEL.w_start, sizeof d->w);
    memcpy(d->u, MODEL.u_start, sizeof d->u);
}

static void changed(Data *d) { d->w_consistent = 0; d->eval_valid = 0; }

/* ODE mode, and Initialization Mode in both modes: the FMU computes w. */
static int fmu_computes_w(const Data *d) {
    return !d->dae || d->state == InitializationMode;
}

static void eval_at(const Data *d, const double w[], double der[], double res[], double y[]) {
    MODEL.eval(d->t, d->x, w, d->u, der, res, y);
}

/* The residuals the Newton iteration drives to zero (ODE mode and initialisation). */
static void eval_solved(const Data *d, const double w[], double der[], double res[],
                        double y[]) {
    eval_at(d, w, der, res, y);
#ifdef DEFECT_ODE_DAE_INCONSISTENT
    if (!d->dae) {   /* ODE mode solves g = 0.05: its w differ from DAE mode's */
        int i;
        for (i = 0; i < NW; i++) res[i] -= 0.05;
    }
#endif
}

static void partials_at(const Data *d, const double w[], double J[]) {
    memset(J, 0, sizeof(double) * EROWS_MAX * ECOLS_MAX);
    MODEL.partials(d->t, d->x, w, d->u, J);
}

/* -------------------------------------------------------- dense LU, Newton */

/* In-place LU with partial pivoting (full row swaps); returns 0 if singular. */
static int lu_factor(int n, double A[], int piv[]) {
    int i, j, k, p;
    for (k = 0; k < n; k++) {
        p = k;
        for (i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > fabs(A[p * n + k])) p = i;
        if (!(fabs(A[p * n + k]) > 0.0) || !isfinite(A[p * n + k])) return 0;
        piv[k] = p;
        if (p != k)
            for (j = 0; j < n; j++) {
                double tmp = A[k * n + j]; A[k * n + j] = A[p * n + j]; A[p * n + j] = tmp;
            }
        for (i = k + 1; i < n; i++) {
            A[i * n + k] /= A[k * n + k];
            for (j = k + 1; j < n; j++) A[i * n + j] -= A[i * n + k] * A[k * n + j];
        }
    }
    return 1;
}

static void lu_solve(int n, const double A[], const int piv[], double b[]) {
    int i, k;
    for (k = 0; k < n; k++) {
        double tmp = b[k]; b[k] = b[piv[k]]; b[piv[k]] = tmp;
    }
    for (i = 1; i < n; i++)
        for (k = 0; k < i; k++) b[i] -= A[i * n + k] * b[k];
    for (i = n - 1; i >= 0; i--) {
        for (k = i + 1; k < n; k++) b[i] -= A[i * n + k] * b[k];
        b[i] /= A[i * n + i];
    }
}

/* dg/dw at the current point, factorised. */
static int factor_gw(const double J[], double G[], int piv[]) {
    int i, k;
    for (i = 0; i < NW; i++)
        for (k = 0; k < NW; k++) G[i * NW + k] = J[(NX + i) * NCOLS + NX + k];
    return lu_factor(NW, G, piv);
}

static double norm2(int n, const double v[]) {
    double s = 0.0;
    int i;
    for (i = 0; i < n; i++) s += v[i] * v[i];
    return sqrt(s);
}

/* Damped Newton iteration for g(t, x, w, u) = 0, warm-started from d->w. */
static int solve_algebraic(Instance *c) {
    Data *d = &c->d;
    double J[EROWS_MAX * ECOLS_MAX], G[NMAX * NMAX];
    double der[NMAX], res[NMAX], y[NMAX], rt[NMAX], wt[NMAX], dw[NMAX];
    int piv[NMAX], i, it, k;

    eval_solved(d, d->w, der, res, y);
    for (it = 0; it < 100; it++) {
        double r0 = norm2(NW, res), lam = 1.0, step = 0.0;
        if (r0 == 0.0) break;
        partials_at(d, d->w, J);
        if (!factor_gw(J, G, piv)) {
            logmsg(c, fmi3Error, "Newton: dg/dw is singular at t=%g", d->t);
            return 0;
        }
        for (i = 0; i < NW; i++) dw[i] = -res[i];
        lu_solve(NW, G, piv, dw);
        for (k = 0; k <= 30; k++, lam *= 0.5) {  /* backtracking on |g| */
            if (k == 30) lam = 1.0;                /* no decrease: take the full step */
            for (i = 0; i < NW; i++) wt[i] = d->w[i] + lam * dw[i];
            eval_solved(d, wt, der, rt, y);
            if (k == 30 || norm2(NW, rt) <= (1.0 - 1e-4 * lam) * r0) break;
        }
        for (i = 0; i < NW; i++) {
            double s = fabs(lam * dw[i]) / fabs(MODEL.w_nominal[i]);
            if (s > step) step = s;
            d->w[i] = wt[i];
            res[i] = rt[i];
        }
        if (!(norm2(NW, res) < INFINITY)) break;
        if (step <= 1e-12) break;
    }
    if (it == 100 || !(norm2(NW, res) < INFINITY)) {
        logmsg(c, fmi3Error, "Newton: no convergence for g = 0 at t=%g", d->t);
        return 0;
    }
    d->w_consistent = 1;
    return 1;
}

/* Bring der, res, y (and w if the FMU computes it) up to date. */
static fmi3Status update(Instance *c) {
    Data *d = &c->d;
    if (!d->w_consistent && (d->state & RUNNING) && fmu_computes_w(d)) {
        if (NW > 0 && !solve_algebraic(c)) return fmi3Error;
        d->w_consistent = 1;
        d->eval_valid = 0;
    }
    if (!d->eval_valid) {
        eval_at(d, d->w, d->der, d->res, d->y);
        d->eval_valid = 1;
    }
    return fmi3OK;
}

/* ----------------------------------------------------- partial derivatives */

/* Row of an unknown in the extended matrix E (rows der, res, y, w) or -1. */
static int unknown_row(const Data *d, fmi3ValueReference vr) {
    int i, kind = lookup(vr, &i);
    if (kind == K_DER) return i;
    if (kind == K_Y) return NX + NW + i;
    if (kind == K_RES && d->dae) return NX + i;
    if (kind == K_W && d->dae && d->state == InitializationMode) return NX + NW + NY + i;
    return -1;
}

/* Column of a known (x, w, u, t) or -1. */
static int known_col(const Data *d, fmi3ValueReference vr) {
    int i, kind = lookup(vr, &i);
    if (kind == K_X) return i;
    if (kind == K_U) return NX + NW + i;
    if (kind == K_TIME) return NX + NW + NU;
    if (kind == K_W && !fmu_computes_w(d)) return NX + i;
    return -1;
}

/* E = partials (DAE mode) or total derivatives with dw/dk = -g_w^-1 g_k. */
static fmi3Status build_E(Instance *c, double E[]) {
    Data *d = &c->d;
    double G[NMAX * NMAX], s[NMAX];
    int piv[NMAX], r, col, i, k;

    if (update(c) != fmi3OK) return fmi3Error;
    partials_at(d, d->w, E);
    if (!fmu_computes_w(d) || NW == 0) return fmi3OK;
    if (!factor_gw(E, G, piv)) FAIL("dg/dw is singular at t=%g", d->t);
    for (col = 0; col < NCOLS; col++) {
        if (col >= NX && col < NX + NW) continue;          /* w is no known here */
        for (i = 0; i < NW; i++) s[i] = E[(NX + i) * NCOLS + col];
        lu_solve(NW, G, piv, s);                           /* s = -dw/dk */
        for (r = 0; r < NX + NW + NY; r++)
            for (k = 0; k < NW; k++) E[r * NCOLS + col] -= E[r * NCOLS + NX + k] * s[k];
        for (i = 0; i < NW; i++) E[(NX + NW + NY + i) * NCOLS + col] = -s[i];
    }
    return fmi3OK;
}

static fmi3Status partial_derivatives(fmi3Instance instance, const char *fn, int adjoint,
                                      const fmi3ValueReference unknowns[], size_t nU,
                                      const fmi3ValueReference knowns[], size_t nK,
                                      const fmi3Float64 seed[], size_t nSeed,
                                      fmi3Float64 sens[], size_t nSens) {
    double E[EROWS_MAX * ECOLS_MAX];
    size_t i, j;
    BEGIN(fn, RUNNING);
    if (nSeed != (adjoint ? nU : nK) || nSens != (adjoint ? nK : nU))
        FAIL("%s: nSeed/nSensitivity do not match the numbers of knowns/unknowns", fn);
    if ((nU && !unknowns) || (nK && !knowns) || (nSeed && !seed) || (nSens && !sens))
        FAIL("%s: NULL argument", fn);
    for (i = 0; i < nU; i++)
        if (unknown_row(&c->d, unknowns[i]) < 0)
            FAIL("%s: %u is not a valid unknown here", fn, (unsigned)unknowns[i]);
    for (j = 0; j < nK; j++)
        if (known_col(&c->d, knowns[j]) < 0)
            FAIL("%s: %u is not a valid known here", fn, (unsigned)knowns[j]);
    if (build_E(c, E) != fmi3OK) return fmi3Error;
    for (i = 0; i < nSens; i++) sens[i] = 0.0;
    for (i = 0; i < nU; i++) {
        int r = unknown_row(&c->d, unknowns[i]);
        for (j = 0; j < nK; j++) {
            double e = E[r * NCOLS + known_col(&c->d, knowns[j])];
#ifdef DEFECT_WRONG_ADJOINT
            if (adjoint && r == NX && known_col(&c->d, knowns[j]) == NX) e *= 2.0;
#endif
            if (adjoint) sens[j] += e * seed[i];
            else         sens[i] += e * seed[j];
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance,
        const fmi3ValueReference unknowns[], size_t nUnknowns,
        const fmi3ValueReference knowns[], size_t nKnowns,
        const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
#ifdef DEFECT_HANG_DIRECTIONAL
    { volatile int spin = 1; while (spin) { } }   /* an iteration without a limit */
#endif
#ifdef DEFECT_FATAL_DIRECTIONAL
    {
        Instance *c = (Instance *)instance;
        logmsg(c, fmi3Fatal, "fmi3GetDirectionalDerivative: internal state corrupted");
        return fmi3Fatal;
    }
#endif
    return partial_derivatives(instance, "fmi3GetDirectionalDerivative", 0, unknowns, nUnknowns,
                               knowns, nKnowns, seed, nSeed, sensitivity, nSensitivity);
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance,
        const fmi3ValueReference unknowns[], size_t nUnknowns,
        const fmi3ValueReference knowns[], size_t nKnowns,
        const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    return partial_derivatives(instance, "fmi3GetAdjointDerivative", 1, unknowns, nUnknowns,
                               knowns, nKnowns, seed, nSeed, sensitivity, nSensitivity);
}

/* --------------------------------------------------- instance life cycle */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn,
                               size_t nCategories, const fmi3String categories[]) {
    BEGIN("fmi3SetDebugLogging", ANY_STATE);
    (void)categories;
    if (nCategories > 0) FAIL("fmi3SetDebugLogging: the model declares no log categories");
    c->logging = loggingOn;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
        fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
        fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage) {
    Instance *c;
    (void)resourcePath; (void)visible;
    if (!instanceName || !instantiationToken ||
        strcmp(instantiationToken, FMU_INSTANTIATION_TOKEN) != 0) {
        if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                                   "fmi3InstantiateModelExchange: wrong instantiationToken");
        return NULL;
    }
    if (NX > NMAX || NW > NMAX || NU > NMAX || NY > NMAX) return NULL;
    c = (Instance *)calloc(1, sizeof *c);
    if (!c) return NULL;
    c->name = (char *)malloc(strlen(instanceName) + 1);
    if (!c->name) { free(c); return NULL; }
    strcpy(c->name, instanceName);
    c->env = instanceEnvironment;
    c->logger = logMessage;
    c->logging = loggingOn;
    reset_data(&c->d);
    return c;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
        fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
        fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
        const fmi3ValueReference requiredIntermediateVariables[],
        size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
        fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible;
    (void)loggingOn; (void)eventModeUsed; (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables; (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                               "Co-Simulation is not supported");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName,
        fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible,
        fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
        fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
        fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible;
    (void)loggingOn; (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                               "Scheduled Execution is not supported");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (!c) return;
    free(c->name);
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
        fmi3Float64 tolerance, fmi3Float64 startTime, fmi3Boolean stopTimeDefined,
        fmi3Float64 stopTime) {
    BEGIN("fmi3EnterInitializationMode", Instantiated);
    (void)toleranceDefined; (void)tolerance;
    if (stopTimeDefined && stopTime < startTime) FAIL("stopTime < startTime");
    c->d.t = startTime;
    c->d.state = InitializationMode;
    changed(&c->d);
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    BEGIN("fmi3ExitInitializationMode", InitializationMode);
#ifdef DEFECT_DAE_INIT_REFUSED
    if (c->d.dae) FAIL("fmi3ExitInitializationMode: initialisation in DAE mode is not supported");
#endif
    if (update(c) != fmi3OK) return fmi3Error;   /* w consistent in both modes */
#ifdef DEFECT_INCONSISTENT_INIT
    if (c->d.dae) {   /* forgets the solved w: the initial point is not consistent */
        memcpy(c->d.w, MODEL.w_start, sizeof c->d.w);
        c->d.eval_valid = 0;
    }
#endif
    c->d.state = EventMode;
    return fmi3OK;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    BEGIN("fmi3EnterEventMode", ContinuousTimeMode);
    c->d.state = EventMode;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    BEGIN("fmi3Terminate", EventMode | ContinuousTimeMode | ReconfigurationMode);
    c->d.state = Terminated;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    BEGIN("fmi3Reset", ANY_STATE);
    reset_data(&c->d);
    return fmi3OK;
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    BEGIN("fmi3EnterConfigurationMode", Instantiated | EventMode);
    if (c->d.state == Instantiated) {
        c->d.state = ConfigurationMode;
        return fmi3OK;
    }
#ifdef DEFECT_NO_RECONFIGURATION
    FAIL("fmi3EnterConfigurationMode: Reconfiguration Mode is not implemented");
#endif
    if (!MODEL.enable_tunable)
        FAIL("fmi3EnterConfigurationMode: no tunable structural parameter");
    if (update(c) != fmi3OK) return fmi3Error;   /* switch from a consistent w */
    c->d.state = ReconfigurationMode;
    return fmi3OK;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    BEGIN("fmi3ExitConfigurationMode", ConfigurationMode | ReconfigurationMode);
    c->d.state = c->d.state == ConfigurationMode ? Instantiated : EventMode;
    c->d.eval_valid = 0;
    if (!c->d.dae) c->d.w_consistent = 0;
    return fmi3OK;
}

/* ------------------------------------------------------- getters, setters */

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues) {
    size_t k;
    int idx, computed = 0;
    BEGIN("fmi3GetFloat64", ANY_STATE);
    if (nvr != nValues) FAIL("fmi3GetFloat64: nValues != nValueReferences");
    if (nvr && (!vr || !values)) FAIL("fmi3GetFloat64: NULL argument");
    for (k = 0; k < nvr; k++) {
        int kind = lookup(vr[k], &idx);
        if (!slot(&c->d, kind, idx)) FAIL("fmi3GetFloat64: no Float64 variable %u", (unsigned)vr[k]);
        computed |= kind == K_DER || kind == K_RES || kind == K_Y || kind == K_W;
#ifdef DEFECT_SEGFAULT_GETFLOAT64
        if (kind == K_RES && c->d.state == ContinuousTimeMode) {
            double *volatile missing = NULL;   /* a buffer that was never allocated */
            values[k] = *missing;
        }
#endif
#ifdef DEFECT_EVAL_ERROR_AFTER_START
        if (kind == K_RES && c->d.dae && c->d.state == ContinuousTimeMode && c->d.t > 0)
            FAIL("fmi3GetFloat64: residual evaluation failed at t=%g", c->d.t);
#endif
    }
    if (computed && update(c) != fmi3OK) return fmi3Error;
    for (k = 0; k < nvr; k++) {
        int kind = lookup(vr[k], &idx);
        values[k] = *slot(&c->d, kind, idx);
    }
    return fmi3OK;
}

static int may_set(const Data *d, int kind) {
    const int running = InitializationMode | EventMode | ContinuousTimeMode;
    switch (kind) {
    case K_X:
    case K_U: return (d->state & (Instantiated | running)) != 0;
#ifdef DEFECT_W_NOT_SETTABLE
    case K_W: return d->state == Instantiated ||
                     (d->dae && (d->state & (InitializationMode | EventMode)));
#else
    case K_W: return d->state == Instantiated || (d->dae && (d->state & running));
#endif
    default:  return 0;
    }
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    size_t k;
    int idx;
    BEGIN("fmi3SetFloat64", ANY_STATE);
    if (nvr != nValues) FAIL("fmi3SetFloat64: nValues != nValueReferences");
    if (nvr && (!vr || !values)) FAIL("fmi3SetFloat64: NULL argument");
    for (k = 0; k < nvr; k++) {
        int kind = lookup(vr[k], &idx);
        if (!slot(&c->d, kind, idx)) FAIL("fmi3SetFloat64: no Float64 variable %u", (unsigned)vr[k]);
        if (!may_set(&c->d, kind))
            FAIL("fmi3SetFloat64: variable %u cannot be set in %s%s", (unsigned)vr[k],
                 state_name(c->d.state), kind == K_W && !c->d.dae ? " (ODE mode)" : "");
    }
    for (k = 0; k < nvr; k++) {
        int kind = lookup(vr[k], &idx);
        *slot(&c->d, kind, idx) = values[k];
    }
    if (nvr) changed(&c->d);
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Boolean values[], size_t nValues) {
    size_t k;
    int idx;
    BEGIN("fmi3GetBoolean", ANY_STATE);
    if (nvr != nValues) FAIL("fmi3GetBoolean: nValues != nValueReferences");
    for (k = 0; k < nvr; k++)
        if (lookup(vr[k], &idx) != K_ENABLE) FAIL("fmi3GetBoolean: no Boolean variable %u", (unsigned)vr[k]);
    for (k = 0; k < nvr; k++) values[k] = c->d.dae;
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues) {
    size_t k;
    int idx;
    BEGIN("fmi3SetBoolean", ANY_STATE);
    if (nvr != nValues) FAIL("fmi3SetBoolean: nValues != nValueReferences");
    for (k = 0; k < nvr; k++)
        if (lookup(vr[k], &idx) != K_ENABLE) FAIL("fmi3SetBoolean: no Boolean variable %u", (unsigned)vr[k]);
    if (nvr && !(c->d.state == ConfigurationMode ||
                 (c->d.state == ReconfigurationMode && MODEL.enable_tunable)))
        FAIL("fmi3SetBoolean: the structural parameter %u cannot be set in %s",
             (unsigned)MODEL.vr_enable, state_name(c->d.state));
    for (k = 0; k < nvr; k++) c->d.dae = values[k] ? fmi3True : fmi3False;
    return fmi3OK;
}

/* The model has no variables of the remaining types. */
static fmi3Status no_variables(fmi3Instance instance, const char *fn, size_t nvr) {
    BEGIN(fn, ANY_STATE);
    if (nvr > 0) FAIL("%s: the model has no variables of this type", fn);
    return fmi3OK;
}

#define NO_VARS(Type)                                                                     \
fmi3Status fmi3Get##Type(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                         fmi3##Type values[], size_t nValues) {                           \
    (void)vr; (void)values; (void)nValues;                                                \
    return no_variables(instance, "fmi3Get" #Type, nvr);                                  \
}                                                                                         \
fmi3Status fmi3Set##Type(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                         const fmi3##Type values[], size_t nValues) {                     \
    (void)vr; (void)values; (void)nValues;                                                \
    return no_variables(instance, "fmi3Set" #Type, nvr);                                  \
}
NO_VARS(Float32)
NO_VARS(Int8)
NO_VARS(UInt8)
NO_VARS(Int16)
NO_VARS(UInt16)
NO_VARS(Int32)
NO_VARS(UInt32)
NO_VARS(Int64)
NO_VARS(UInt64)
NO_VARS(String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)vr; (void)valueSizes; (void)values; (void)nValues;
    return no_variables(instance, "fmi3GetBinary", nvr);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)vr; (void)valueSizes; (void)values; (void)nValues;
    return no_variables(instance, "fmi3SetBinary", nvr);
}

#ifndef DEFECT_MISSING_EXPORT
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[]) {
    (void)vr; (void)values;
    return no_variables(instance, "fmi3GetClock", nvr);
}
#endif

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[]) {
    (void)vr; (void)values;
    return no_variables(instance, "fmi3SetClock", nvr);
}

/* ------------------------------------------------------ Model Exchange */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    BEGIN("fmi3EnterContinuousTimeMode", EventMode);
    c->d.state = ContinuousTimeMode;
    return fmi3OK;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
        fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
        fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
        fmi3Float64 *nextEventTime) {
    BEGIN("fmi3UpdateDiscreteStates", EventMode);
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = fmi3False;
    if (nextEventTimeDefined) *nextEventTimeDefined = fmi3False;
    if (nextEventTime) *nextEventTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
        fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *enterEventMode,
        fmi3Boolean *terminateSimulation) {
    BEGIN("fmi3CompletedIntegratorStep", ContinuousTimeMode);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (enterEventMode) *enterEventMode = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    BEGIN("fmi3SetTime", ContinuousTimeMode);
#ifdef DEFECT_EXIT_IN_CALL
    if (time > 0) exit(3);   /* "cannot continue": ends the importer's process */
#endif
    if (!isfinite(time)) FAIL("fmi3SetTime: time is not finite");
    c->d.t = time;
    changed(&c->d);
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t nx) {
    BEGIN("fmi3SetContinuousStates", ContinuousTimeMode);
    if (nx != (size_t)NX || (nx && !x)) FAIL("fmi3SetContinuousStates: expected %d states", NX);
    memcpy(c->d.x, x, nx * sizeof(double));
    changed(&c->d);
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 der[], size_t nx) {
    BEGIN("fmi3GetContinuousStateDerivatives", RUNNING);
    if (nx != (size_t)NX || (nx && !der)) FAIL("fmi3GetContinuousStateDerivatives: expected %d", NX);
#ifdef DEFECT_MEMORY_BLOWUP
    for (;;) {   /* a runaway cache: grows until malloc fails, then aborts */
        char *block = (char *)malloc((size_t)64 << 20);
        if (!block) abort();
        memset(block, 1, (size_t)64 << 20);
    }
#endif
#ifdef DEFECT_ODE_DERIVATIVES_FAIL
    if (!c->d.dae) FAIL("fmi3GetContinuousStateDerivatives: not available in ODE mode");
#endif
    if (update(c) != fmi3OK) return fmi3Error;
    memcpy(der, c->d.der, nx * sizeof(double));
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t nx) {
    BEGIN("fmi3GetContinuousStates", RUNNING);
    if (nx != (size_t)NX || (nx && !x)) FAIL("fmi3GetContinuousStates: expected %d states", NX);
    memcpy(x, c->d.x, nx * sizeof(double));
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nx) {
    BEGIN("fmi3GetNominalsOfContinuousStates", Instantiated | RUNNING);
    if (nx != (size_t)NX || (nx && !nominals)) FAIL("fmi3GetNominalsOfContinuousStates: expected %d", NX);
    memcpy(nominals, MODEL.x_nominal, nx * sizeof(double));
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 z[], size_t nz) {
    BEGIN("fmi3GetEventIndicators", RUNNING);
    (void)z;
    if (nz != 0) FAIL("fmi3GetEventIndicators: the model has no event indicators");
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) {
    BEGIN("fmi3GetNumberOfEventIndicators", NOT_CONFIG);
    if (!n) FAIL("fmi3GetNumberOfEventIndicators: NULL argument");
    *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) {
    BEGIN("fmi3GetNumberOfContinuousStates", NOT_CONFIG);
    if (!n) FAIL("fmi3GetNumberOfContinuousStates: NULL argument");
    *n = (size_t)NX;
    return fmi3OK;
}

/* ------------------------------------------------------------ FMU state */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *state) {
    BEGIN("fmi3GetFMUState", NOT_CONFIG);
    if (!state) FAIL("fmi3GetFMUState: NULL argument");
    if (!*state && !(*state = malloc(sizeof(Data)))) FAIL("fmi3GetFMUState: out of memory");
    memcpy(*state, &c->d, sizeof(Data));
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state) {
    BEGIN("fmi3SetFMUState", NOT_CONFIG);
    if (!state) FAIL("fmi3SetFMUState: NULL state");
    memcpy(&c->d, state, sizeof(Data));
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *state) {
    BEGIN("fmi3FreeFMUState", ANY_STATE);
    if (state) { free(*state); *state = NULL; }
    return fmi3OK;
}

/* --------------------------------------------------------- unsupported */

static fmi3Status unsupported(fmi3Instance instance, const char *fn) {
    Instance *c = (Instance *)instance;
    FAIL("%s is not supported by this FMU", fn);
}

#define UNSUPPORTED(fn) { return unsupported(instance, #fn); }

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState s, size_t *size)
{ (void)s; (void)size; UNSUPPORTED(fmi3SerializedFMUStateSize) }
fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState s, fmi3Byte b[], size_t n)
{ (void)s; (void)b; (void)n; UNSUPPORTED(fmi3SerializeFMUState) }
fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte b[], size_t n,
                                   fmi3FMUState *s)
{ (void)s; (void)b; (void)n; UNSUPPORTED(fmi3DeserializeFMUState) }
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                               size_t *n)
{ (void)vr; (void)n; UNSUPPORTED(fmi3GetNumberOfVariableDependencies) }
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
        size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
        size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[], size_t n)
{ (void)dependent; (void)elementIndicesOfDependent; (void)independents;
  (void)elementIndicesOfIndependents; (void)dependencyKinds; (void)n;
  UNSUPPORTED(fmi3GetVariableDependencies) }
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
        size_t nvr, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
{ (void)vr; (void)nvr; (void)intervals; (void)qualifiers; UNSUPPORTED(fmi3GetIntervalDecimal) }
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
        size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
        fmi3IntervalQualifier qualifiers[])
{ (void)vr; (void)nvr; (void)counters; (void)resolutions; (void)qualifiers;
  UNSUPPORTED(fmi3GetIntervalFraction) }
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
        size_t nvr, fmi3Float64 shifts[])
{ (void)vr; (void)nvr; (void)shifts; UNSUPPORTED(fmi3GetShiftDecimal) }
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[],
        size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{ (void)vr; (void)nvr; (void)counters; (void)resolutions; UNSUPPORTED(fmi3GetShiftFraction) }
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
        size_t nvr, const fmi3Float64 intervals[])
{ (void)vr; (void)nvr; (void)intervals; UNSUPPORTED(fmi3SetIntervalDecimal) }
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
        size_t nvr, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{ (void)vr; (void)nvr; (void)counters; (void)resolutions; UNSUPPORTED(fmi3SetIntervalFraction) }
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
        size_t nvr, const fmi3Float64 shifts[])
{ (void)vr; (void)nvr; (void)shifts; UNSUPPORTED(fmi3SetShiftDecimal) }
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[],
        size_t nvr, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{ (void)vr; (void)nvr; (void)counters; (void)resolutions; UNSUPPORTED(fmi3SetShiftFraction) }
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{ UNSUPPORTED(fmi3EvaluateDiscreteStates) }
fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{ UNSUPPORTED(fmi3EnterStepMode) }
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
        size_t nvr, const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues)
{ (void)vr; (void)nvr; (void)orders; (void)values; (void)nValues;
  UNSUPPORTED(fmi3GetOutputDerivatives) }
fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
        fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
        fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
        fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{ (void)currentCommunicationPoint; (void)communicationStepSize;
  (void)noSetFMUStatePriorToCurrentPoint; (void)eventHandlingNeeded;
  (void)terminateSimulation; (void)earlyReturn; (void)lastSuccessfulTime;
  UNSUPPORTED(fmi3DoStep) }
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
        fmi3Float64 activationTime)
{ (void)clockReference; (void)activationTime; UNSUPPORTED(fmi3ActivateModelPartition) }
