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
 * Events (models that declare them, see dae_model.h): the event indicators z are computed
 * with der, res and y, from the current (t, x, w, u, d); fmi3UpdateDiscreteStates runs the
 * model's event hook, which may change the discrete variables d (and x) and announce the
 * next time event.  A model without events has nz = nd = 0 and behaves as before.
 *
 * Every work array is allocated on the heap at instantiation, sized from the
 * model.  The model's Jacobian is kept as a list of entries: its declared
 * pattern (sparse models, see dae_model.h) or every entry (dense models).
 * Directional and adjoint derivatives are products with that list, total
 * derivatives add one solve with dg/dw, and dg/dw is factorised in band
 * storage with the bandwidth of the pattern (a dense model's band is full:
 * the same operations as a dense LU).  So a banded sparse model costs O(nnz)
 * per derivative call and per Newton step; value references are looked up by
 * binary search.
 *
 * Illegal calls return fmi3Error and leave the instance unchanged.
 *
 * Defect variants for the probe tests (tests/fixtures/defects/basic.py and derivatives.py;
 * tests/fixtures/README.md lists every switch of every scene), each
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
 *   DEFECT_INPUT_NOT_SETTABLE      DAE mode: fmi3SetFloat64 on an input returns fmi3Error in
 *                                  Continuous-Time Mode and the instance goes to Terminated
 *   DEFECT_ZERO_DIRECTIONAL        fmi3GetDirectionalDerivative returns zeros (fmi3OK)
 *   DEFECT_EVAL_ERROR_AFTER_START  DAE mode: reading residuals fails once time has advanced
 *   DEFECT_MISSING_EXPORT          fmi3GetClock is not exported
 *   DEFECT_DAE_ONLY                always in DAE mode, as if the switch were stuck at true
 *   DEFECT_FATAL_DIRECTIONAL       fmi3GetDirectionalDerivative returns fmi3Fatal
 *   DEFECT_WRONG_ADJOINT           the adjoint alone doubles d(res[0])/d(w[0]) (DAE mode)
 *   DEFECT_ODE_DIRECTIONAL_OFF     ODE mode, Continuous-Time Mode: the directional derivative's
 *                                  d der(x[0])/d x[0] is 10 % too large (DAE mode stays right)
 *   DEFECT_ODE_DAE_INCONSISTENT    ODE mode solves g = 0.05 instead of g = 0
 *   DEFECT_RESET_KEEPS_SWITCH      fmi3Reset keeps the DAE switch and the first state
 *   DEFECT_INITIAL_UNDECLARED      Initialization Mode: y[0] also depends on x[NX-1] (its value
 *                                  and its derivatives agree; the XML does not say so)
 *   DEFECT_INITIAL_DIRECTIONAL     Initialization Mode, DAE mode: the directional derivative of
 *                                  w drops the sign of -(dg/dw)^-1 dg/dk
 * and for the importer-path probes (tests/fixtures/defects/importers.py):
 *   DEFECT_STATE_SET_IGNORED       fmi3SetFloat64 on a state returns fmi3OK in Continuous-Time Mode
 *                                  but keeps the old value
 *   DEFECT_STATE_SET_REFUSED       fmi3SetFloat64 on a state returns fmi3Error in Continuous-Time Mode
 *   DEFECT_INDICATORS_STALE        event indicators computed from the previous evaluation's w
 *   DEFECT_INDICATOR_COUNT         fmi3GetNumberOfEventIndicators says one more than there are
 * and for the simulation probes (tests/fixtures/defects/simulation.py), only for t > 0.5:
 *   DEFECT_LATE_JUMP               res[0] jumps by 1 (no event indicator)
 *   DEFECT_LATE_FAST               der[0] gains 1e5 cos(1e5 t)
 *   DEFECT_LATE_ODE_DRIFT          ODE mode solves g = 0.05 instead of g = 0
 * and for the endurance probes (tests/fixtures/defects/endurance.py), only with sustained use:
 *   DEFECT_LATE_CRASH              Continuous-Time Mode: the 5001st FMI call on an instance crashes
 *   DEFECT_LATE_ERROR              Continuous-Time Mode: every FMI call after the 5000th on an
 *                                  instance returns fmi3Error
 *   DEFECT_LATE_AFTER=<n>          the two above strike after n calls instead of 5000
 *   DEFECT_LATE_CALL=<function>    ... and only in that FMI function
 *   DEFECT_LEAK                    fmi3GetFloat64 keeps 1 KiB on every call, never freed
 *   DEFECT_LEAK_CALL=<function>    that FMI function keeps DEFECT_LEAK_BYTES=<n> (default 1024)
 *                                  bytes on every call, never freed (the leak family)
 *   DEFECT_GLOBAL_STATE            the states x live in one C global shared by every instance
 *   DEFECT_STALE_STATES            a new instance starts from the states of the last one freed
 * and for the read-back probes (tests/fixtures/defects/readback.py), each aimed by READ_KIND
 * (K_TIME, K_X, ... K_D), READ_STATES (a mask of states) and READ_DAE (1 DAE mode, 0 ODE, -1 both):
 *   DEFECT_GET_REFUSED             fmi3GetFloat64 refuses the variables aimed at
 *   DEFECT_GET_NAN                 fmi3GetFloat64 returns NaN for them
 *   DEFECT_GET_UNWRITTEN           fmi3GetFloat64 leaves their elements of values[] unwritten
 *   DEFECT_STALE_READ              fmi3GetFloat64 of READ_KIND alone does not update the evaluation
 *   DEFECT_SET_KEEPS_CACHE         a setter keeps the cache (KEEPS_CACHE_ON: 1 fmi3SetTime,
 *                                  2 fmi3SetContinuousStates, 3 fmi3SetFloat64; READ_DAE's mode)
 *   DEFECT_VECTOR_DERIVATIVES      fmi3GetContinuousStateDerivatives: the last element is off by 1e-6
 *   DEFECT_VECTOR_STATES           fmi3GetContinuousStates: the last element is off by 1e-6
 *   DEFECT_NOMINAL_INVALID         fmi3GetNominalsOfContinuousStates gives NOMINAL_VALUE first
 *   DEFECT_NOMINAL_UNWRITTEN       fmi3GetNominalsOfContinuousStates leaves the first unwritten
 *   DEFECT_NOMINAL_NOT_XML         fmi3GetNominalsOfContinuousStates: the first is 1.1 times the XML's
 *   DEFECT_RESET_KEEPS_TIME        fmi3Reset keeps time and the evaluation cache
 *   DEFECT_RESET_KEEPS_GUESS       fmi3Reset keeps the algebraic variables' last values
 *   DEFECT_RESET_KEEPS_GUESS_DAE   ... and gives them back when DAE mode is switched on again
 *   DEFECT_W_START_DAE             switching DAE mode on in Configuration Mode moves the first
 *                                  algebraic variable 0.5 off its XML start (DAE mode only)
 * and for the event and call probes (tests/fixtures/defects/events.py):
 *   DEFECT_EVENT_OUTPUTS_UNWRITTEN fmi3UpdateDiscreteStates returns fmi3OK without running the
 *                                  event or writing its output arguments
 *   DEFECT_NEXT_EVENT_PAST=<dt>    nextEventTime = t - dt announced whenever the model announces none
 *   DEFECT_EVENT_STALE             a change of the discrete variables is not noticed (values read
 *                                  at the event instant are those before it)
 *   DEFECT_STATES_CHANGED_SPURIOUS valuesOfContinuousStatesChanged is true at every event
 *   DEFECT_STOP_TIME_REFUSED       fmi3EnterInitializationMode refuses any defined stop time
 *   DEFECT_SETBOOLEAN_ANY_VR       fmi3SetBoolean takes any value reference for the switch
 *   DEFECT_KNOWN_UNCHECKED         a directional/adjoint known that is no known is taken as x[0]
 *   DEFECT_SEED_SIZE_UNCHECKED     nSeed and nSensitivity are not checked against the counts
 *   DEFECT_CRASH_ON_ILLEGAL_KNOWN  an output given as a known dereferences NULL (crash)
 *   DEFECT_SHARED=<what>           a C global holds the values, partial derivatives, DAE switch
 *                                  or inputs of the instances DEFECT_SHARED_BY=<1|2|SHARED_EVERY>
 *                                  names, and the others read it (the shared-state family)
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dae_model.h"

#ifndef FMU_INSTANTIATION_TOKEN
#error "compile with -DFMU_INSTANTIATION_TOKEN=\"...\" (scenes/build.py does)"
#endif

#define NMAX      FMU_MAX_VARS            /* capacity of the model's tables only */
#define NX        MODEL.nx
#define NW        MODEL.nw
#define NU        MODEL.nu
#define NY        MODEL.ny
#define ND        MODEL.nd
#define NZ        MODEL.nz
#define NROWS     (NX + NW + NY)          /* rows der, res, y of the model's Jacobian */
#define NCOLS     (NX + NW + NU + 1)      /* columns x, w, u, t */
#define NVALUES   (2 * NX + 2 * NW + NU + NY + NZ + ND)
#define MAX_BLOCKS 40

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
#define BEFORE_INIT_EXIT (Instantiated | ConfigurationMode | InitializationMode)

/* The scalars of what fmi3GetFMUState saves (the values are in Instance.vals). */
typedef struct {
    ModelState  state;
    fmi3Boolean dae;
    double t;
    int w_consistent;  /* w solves g = 0 for the current (t, x, u) */
    int eval_valid;    /* der, res, y are up to date */
} Data;

typedef struct {
    Data d;
    double vals[];     /* x, w, u, der, res, y, z, d */
} SavedState;

typedef struct {
    fmi3ValueReference vr;
    int kind, idx, seq;
} VrEntry;

typedef struct {
    fmi3ValueReference vr;
    fmi3DependencyKind kind;
} Dependency;

typedef struct {
    Data d;
    double *vals, *x, *w, *u, *der, *res, *y;
    double *ind, *disc;                /* event indicators z, discrete variables d */
    double *xsave, *dsave;             /* x and d before the event hook */
#ifdef DEFECT_INDICATORS_STALE
    double *wlast;                     /* the w of the previous evaluation */
#endif

    /* the model's Jacobian: pattern and values at the last evaluation */
    int nnz;
    ModelEntry *pat;
    double *pval;
    /* dg/dw, band storage: row i holds columns i-kl .. i+kl+ku (room for the fill-in) */
    int kl, ku, bw;
    double *ab;
    int *piv;
    /* scratch */
    double *s, *s2, *p, *p2;           /* NCOLS */
    double *v, *v2, *a, *a2;           /* NROWS */
    double *z, *nres, *rt, *wt, *dw;   /* NW */
    double *nder, *ny;                 /* NX, NY */
    /* value references, sorted, and a direct table when they are dense enough */
    VrEntry *index;
    int nindex;
    int *direct;                       /* vr - vr_min -> position in index, or -1 */
    fmi3ValueReference vr_min, vr_span;
    /* structure for the per-element dependencies (sparse models only) */
    int *rowptr, *rowent;              /* pattern entries by row */
    int *comp;                         /* component of each w in the graph of dg/dw */
    int *compptr, *compcol;            /* the knowns of each component's residuals */
    int *colstamp, *compstamp, stamp;
    fmi3DependencyKind *colkind;
    int *depcol;
    Dependency *deps;

    void *blocks[MAX_BLOCKS];
    int nblocks, alloc_failed;

    char *name;
    unsigned long ncalls;              /* FMI calls on this instance (DEFECT_LATE_*) */
#ifdef DEFECT_RESET_KEEPS_GUESS_DAE
    int guess_kept;                    /* fmi3Reset kept w in wt, for DAE mode to take back */
#endif
#ifdef DEFECT_SHARED
    int ordinal;                       /* 1 for the process's first instance, 2, ... */
    int partials_valid;                /* pval is up to date (a cache, derivatives variant) */
#endif
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback  logger;
    fmi3Boolean logging;
} Instance;

enum { K_NONE, K_TIME, K_ENABLE, K_X, K_DER, K_W, K_RES, K_U, K_Y, K_Z, K_D };

/* The variables the read-back defects aim at (DEFECT_GET_*, DEFECT_STALE_READ, DEFECT_VECTOR_*). */
#ifndef READ_KIND
#define READ_KIND K_TIME
#endif
#ifndef READ_STATES
#define READ_STATES ANY_STATE
#endif
#ifndef READ_DAE
#define READ_DAE (-1)
#endif
#define READ_AIMED(c, kind) ((kind) == READ_KIND && ((c)->d.state & (READ_STATES)) && \
                             (READ_DAE < 0 || (int)(c)->d.dae == READ_DAE))
#define READ_MODE(c) (READ_DAE < 0 || (int)(c)->d.dae == READ_DAE)
#ifndef KEEPS_CACHE_ON
#define KEEPS_CACHE_ON 1
#endif

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

/* Set by model_discard() while the model is evaluated; reset by update(). */
static const char *discard_reason;

void model_discard(const char *reason) {
    if (!discard_reason) discard_reason = reason ? reason : "the model cannot be evaluated here";
}

static fmi3Status discarded(Instance *c) {
    logmsg(c, fmi3Discard, "t=%g: %s", c->d.t, discard_reason);
    return fmi3Discard;
}

#define FAIL(...) do { logmsg(c, fmi3Error, __VA_ARGS__); return fmi3Error; } while (0)

/* The defects that need sustained use: they strike after LATE_AFTER calls on one instance
 * (DEFECT_LATE_AFTER=<n> sets another count, DEFECT_LATE_CALL=<FMI function> strikes in that
 * function only: the family of late failures, tests/probes/test_late_family.py). */
#ifdef DEFECT_LATE_AFTER
#define LATE_AFTER ((unsigned long)(DEFECT_LATE_AFTER))
#else
#define LATE_AFTER 5000UL
#endif
#ifdef DEFECT_LATE_CALL
#define LATE_NAME_(x) #x
#define LATE_NAME(x) LATE_NAME_(x)
#define LATE_IN(fn) (strcmp((fn), LATE_NAME(DEFECT_LATE_CALL)) == 0)
#else
#define LATE_IN(fn) 1
#endif
#if defined(DEFECT_LATE_CRASH)
#define LATE(fn)                                                               \
    if (++c->ncalls > LATE_AFTER && c->d.state == ContinuousTimeMode && LATE_IN(fn)) { \
        double *volatile gone = NULL;   /* a work buffer released too early */ \
        c->d.t = *gone;                                                        \
    }
#elif defined(DEFECT_LATE_ERROR)
#define LATE(fn)                                                               \
    if (++c->ncalls > LATE_AFTER && c->d.state == ContinuousTimeMode && LATE_IN(fn)) \
        FAIL("%s: work buffer exhausted after %lu calls", fn, LATE_AFTER)
#else
#define LATE(fn)
#endif

/* Declares `c`, checks the instance pointer and the state mask. */
#define BEGIN(fn, mask)                                                        \
    Instance *c = (Instance *)instance;                                        \
    if (!c) return fmi3Error;                                                  \
    LATE(fn);                                                                  \
    LEAK(fn);                                                                  \
    SHARED_SYNC(c);                                                            \
    if (!(c->d.state & (mask)))                                                \
        FAIL("%s: not allowed in %s", fn, state_name(c->d.state))

/*
 * Leaks, a family (tests/probes/test_leak_family.py): DEFECT_LEAK_CALL=<FMI function> keeps
 * DEFECT_LEAK_BYTES (default 1024) bytes, written, on every call of that function, never freed:
 * any function that opens with BEGIN, fmi3InstantiateModelExchange or fmi3FreeInstance.
 * DEFECT_LEAK is the first member: 1 KiB per fmi3GetFloat64.
 */
#if defined(DEFECT_LEAK) && !defined(DEFECT_LEAK_CALL)
#define DEFECT_LEAK_CALL fmi3GetFloat64
#endif
#ifdef DEFECT_LEAK_CALL
#ifndef DEFECT_LEAK_BYTES
#define DEFECT_LEAK_BYTES 1024
#endif
#define LEAK_NAME_(x) #x
#define LEAK_NAME(x) LEAK_NAME_(x)
static void *leaked;                   /* a result cache that only grows */
static void leak(const char *fn) {
    void **block;
    if (strcmp(fn, LEAK_NAME(DEFECT_LEAK_CALL)) != 0) return;
    block = (void **)malloc((size_t)(DEFECT_LEAK_BYTES) < sizeof(void *) ? sizeof(void *)
                            : (size_t)(DEFECT_LEAK_BYTES));
    if (!block) return;
    memset(block, 1, (size_t)(DEFECT_LEAK_BYTES) < sizeof(void *) ? sizeof(void *)
           : (size_t)(DEFECT_LEAK_BYTES));
    block[0] = leaked;
    leaked = block;
}
#define LEAK(fn) leak(fn)
#else
#define LEAK(fn)
#endif

/*
 * State shared between instances, a family (tests/probes/test_shared_family.py): a C global
 * holds what each instance should keep for itself.  DEFECT_SHARED says what:
 *   SHARED_VALUES       the results of the last evaluation (derivatives, residuals, outputs)
 *   SHARED_DERIVATIVES  the partial derivatives (cached per point, as generated code does)
 *   SHARED_MODE         the DAE switch
 *   SHARED_INPUTS       the inputs
 * and DEFECT_SHARED_BY which instances write it: 1 (the process's first instance), 2 (the
 * second) or SHARED_EVERY.  The others read it instead of their own copy once it was written
 * (with SHARED_EVERY every instance writes and reads it: one copy for all).  An instance alone
 * in its process (in its own copy of the library) computes right in every member.
 */
#define SHARED_VALUES 1
#define SHARED_DERIVATIVES 2
#define SHARED_MODE 3
#define SHARED_INPUTS 4
#define SHARED_EVERY 0
#ifdef DEFECT_SHARED
#ifndef DEFECT_SHARED_BY
#define DEFECT_SHARED_BY SHARED_EVERY
#endif
static int shared_created;             /* instances instantiated in this process */
static int shared_set;                 /* the global was written */
static double shared_values[3 * NMAX]; /* der, res, y */
static double *shared_partials;        /* nnz values, allocated when first written */
static fmi3Boolean shared_dae;
static double shared_u[NMAX];
#define SHARED_WRITES(c) (DEFECT_SHARED_BY == SHARED_EVERY || (c)->ordinal == DEFECT_SHARED_BY)
#define SHARED_READS(c) (DEFECT_SHARED_BY == SHARED_EVERY || (c)->ordinal != DEFECT_SHARED_BY)
static void changed(Data *d);
static void shared_sync(void *instance);
#define SHARED_SYNC(c) shared_sync(c)
#else
#define SHARED_SYNC(c)
#endif
#ifdef DEFECT_GLOBAL_STATE
static double global_x[NMAX];          /* generated code's one state vector for every instance */
#endif
#ifdef DEFECT_STALE_STATES
static double stale_x[NMAX];           /* a static state vector, set only when the library loads */
static int have_stale;
#endif

/* A zeroed heap block owned by the instance (freed with it); NULL once one failed. */
static void *grab(Instance *c, size_t n, size_t size) {
    void *block;
    if (c->alloc_failed || c->nblocks == MAX_BLOCKS) {
        c->alloc_failed = 1;
        return NULL;
    }
    block = calloc(n ? n : 1, size);
    if (!block) {
        c->alloc_failed = 1;
        return NULL;
    }
    c->blocks[c->nblocks++] = block;
    return block;
}

static int compare_vr(const void *pa, const void *pb) {
    const VrEntry *a = (const VrEntry *)pa, *b = (const VrEntry *)pb;
    if (a->vr != b->vr) return a->vr < b->vr ? -1 : 1;
    return a->seq - b->seq;
}

static void index_add(Instance *c, fmi3ValueReference vr, int kind, int idx) {
    VrEntry *e = &c->index[c->nindex];
    e->vr = vr; e->kind = kind; e->idx = idx; e->seq = c->nindex++;
}

/* The sorted value-reference table (a duplicate resolves to the first in this order). */
static void build_index(Instance *c) {
    int i;
    index_add(c, MODEL.vr_time, K_TIME, 0);
    index_add(c, MODEL.vr_enable, K_ENABLE, 0);
    for (i = 0; i < NX; i++) { index_add(c, MODEL.vr_x[i], K_X, i); index_add(c, MODEL.vr_der[i], K_DER, i); }
    for (i = 0; i < NW; i++) { index_add(c, MODEL.vr_w[i], K_W, i); index_add(c, MODEL.vr_res[i], K_RES, i); }
    for (i = 0; i < NU; i++) index_add(c, MODEL.vr_u[i], K_U, i);
    for (i = 0; i < NY; i++) index_add(c, MODEL.vr_y[i], K_Y, i);
    for (i = 0; i < NZ; i++) index_add(c, MODEL.vr_z[i], K_Z, i);
    for (i = 0; i < ND; i++) index_add(c, MODEL.vr_d[i], K_D, i);
    qsort(c->index, (size_t)c->nindex, sizeof *c->index, compare_vr);
    c->vr_min = c->index[0].vr;
    c->vr_span = c->index[c->nindex - 1].vr - c->vr_min + 1;
    if (c->vr_span <= 4 * (fmi3ValueReference)c->nindex + 64 &&
        (c->direct = (int *)grab(c, (size_t)c->vr_span, sizeof(int)))) {
        for (i = 0; i < (int)c->vr_span; i++) c->direct[i] = -1;
        for (i = c->nindex - 1; i >= 0; i--) c->direct[c->index[i].vr - c->vr_min] = i;
    }
}

static int lookup(const Instance *c, fmi3ValueReference vr, int *idx) {
    int lo = 0, hi = c->nindex;          /* first entry with index[k].vr >= vr */
    *idx = 0;
    if (c->direct) {
        if (vr < c->vr_min || vr - c->vr_min >= c->vr_span) return K_NONE;
        if ((lo = c->direct[vr - c->vr_min]) < 0) return K_NONE;
        *idx = c->index[lo].idx;
        return c->index[lo].kind;
    }
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (c->index[mid].vr < vr) lo = mid + 1; else hi = mid;
    }
    if (lo == c->nindex || c->index[lo].vr != vr) return K_NONE;
    *idx = c->index[lo].idx;
    return c->index[lo].kind;
}

static double *slot(Instance *c, int kind, int i) {
    switch (kind) {
    case K_TIME: return &c->d.t;
    case K_X:    return &c->x[i];
    case K_DER:  return &c->der[i];
    case K_W:    return &c->w[i];
    case K_RES:  return &c->res[i];
    case K_U:    return &c->u[i];
    case K_Y:    return &c->y[i];
    case K_Z:    return &c->ind[i];
    case K_D:    return &c->disc[i];
    default:     return NULL;
    }
}

static void reset_data(Instance *c) {
    memset(&c->d, 0, sizeof c->d);
    memset(c->vals, 0, sizeof(double) * (size_t)NVALUES);
    c->d.state = Instantiated;
#ifdef DEFECT_DAE_ONLY
    c->d.dae = fmi3True;   /* a "DAE-only" FMU of the first exporter releases */
#else
    c->d.dae = fmi3False;
#endif
    memcpy(c->x, MODEL.x_start, sizeof(double) * (size_t)NX);
    memcpy(c->w, MODEL.w_start, sizeof(double) * (size_t)NW);
    memcpy(c->u, MODEL.u_start, sizeof(double) * (size_t)NU);
    memcpy(c->disc, MODEL.d_start, sizeof(double) * (size_t)ND);
}

static void changed(Data *d) { d->w_consistent = 0; d->eval_valid = 0; }

#ifdef DEFECT_SHARED
/* At the start of every call: a reading instance takes what the global holds. */
static void shared_sync(void *instance) {
    Instance *c = (Instance *)instance;
    if (!shared_set || !SHARED_READS(c)) return;
#if DEFECT_SHARED == SHARED_MODE
    if (c->d.dae != shared_dae) {
        c->d.dae = shared_dae;
        changed(&c->d);
    }
#elif DEFECT_SHARED == SHARED_INPUTS
    if (NU > 0 && memcmp(c->u, shared_u, sizeof(double) * (size_t)NU) != 0) {
        memcpy(c->u, shared_u, sizeof(double) * (size_t)NU);
        changed(&c->d);
    }
#endif
}

#if DEFECT_SHARED == SHARED_VALUES
/* After an evaluation: the results a reading instance returns are the global's. */
static void shared_read_values(Instance *c) {
    if (shared_set && SHARED_READS(c))
        memcpy(c->der, shared_values, sizeof(double) * (size_t)(NX + NW + NY));
}
#endif
#endif

/* ODE mode, and Initialization Mode in both modes: the FMU computes w. */
static int fmu_computes_w(const Instance *c) {
    return !c->d.dae || c->d.state == InitializationMode;
}

static void eval_at(const Instance *c, const double w[], double der[], double res[], double y[]) {
    if (MODEL.eval_discrete) MODEL.eval_discrete(c->d.t, c->x, w, c->u, c->disc, der, res, y);
    else                     MODEL.eval(c->d.t, c->x, w, c->u, der, res, y);
#ifdef DEFECT_LATE_JUMP
    if (c->d.t > 0.5 && NW > 0) res[0] += 1.0;
#endif
#ifdef DEFECT_LATE_FAST
    if (c->d.t > 0.5 && NX > 0) der[0] += 1e5 * cos(1e5 * c->d.t);
#endif
}

/* The event indicators at (t, x, w, u, d) into ind. */
static void indicators_at(const Instance *c, const double w[]) {
    MODEL.indicators(c->d.t, c->x, w, c->u, c->disc, c->ind);
}

/* The residuals the Newton iteration drives to zero (ODE mode and initialisation). */
static void eval_solved(const Instance *c, const double w[], double der[], double res[],
                        double y[]) {
    eval_at(c, w, der, res, y);
#ifdef DEFECT_ODE_DAE_INCONSISTENT
    if (!c->d.dae) {   /* ODE mode solves g = 0.05: its w differ from DAE mode's */
        int i;
        for (i = 0; i < NW; i++) res[i] -= 0.05;
    }
#endif
#ifdef DEFECT_LATE_ODE_DRIFT
    if (!c->d.dae && c->d.t > 0.5) {   /* from t = 0.5 ODE mode drifts away from DAE mode */
        int i;
        for (i = 0; i < NW; i++) res[i] -= 0.05;
    }
#endif
}

/* The model's partial derivatives at (t, x, w, u) into pval (the pattern's order). */
static void partials_at(Instance *c, const double w[]) {
    memset(c->pval, 0, sizeof(double) * (size_t)c->nnz);
    if (MODEL.pattern) MODEL.partials_sparse(c->d.t, c->x, w, c->u, c->pval);
    else if (MODEL.partials_discrete)
        MODEL.partials_discrete(c->d.t, c->x, w, c->u, c->disc, c->pval);
    else               MODEL.partials(c->d.t, c->x, w, c->u, c->pval);
}

/* ---------------------------------------------------------- the Jacobian's pattern */

/* The pattern (declared, or every entry of a dense model) and the band of dg/dw. */
static int load_pattern(Instance *c) {
    int k, n;
    if (MODEL.pattern) {
        if (!MODEL.partials_sparse) {
            logmsg(c, fmi3Error, "the model declares a pattern but no partials_sparse");
            return 0;
        }
        n = MODEL.pattern(NULL);
        if (n < 0 || !(c->pat = (ModelEntry *)grab(c, (size_t)n, sizeof *c->pat))) return 0;
        if (MODEL.pattern(c->pat) != n) {
            logmsg(c, fmi3Error, "the model's pattern changed size between two calls");
            return 0;
        }
        for (k = 0; k < n; k++) {
            ModelEntry *e = &c->pat[k];
            if (e->row < 0 || e->row >= NROWS || e->col < 0 || e->col >= NCOLS) {
                logmsg(c, fmi3Error, "pattern entry %d (%d, %d) is out of range", k, e->row, e->col);
                return 0;
            }
            if (e->kind == fmi3Independent) e->kind = fmi3Dependent;
        }
    } else {
        if (!MODEL.partials && !MODEL.partials_discrete) {
            logmsg(c, fmi3Error, "the model has neither partials nor a pattern");
            return 0;
        }
        n = NROWS * NCOLS;                 /* row-major: pval is the dense J of dae_model.h */
        if (!(c->pat = (ModelEntry *)grab(c, (size_t)n, sizeof *c->pat))) return 0;
        for (k = 0; k < n; k++) {
            c->pat[k].row = k / NCOLS;
            c->pat[k].col = k % NCOLS;
            c->pat[k].kind = fmi3Dependent;
        }
    }
    c->nnz = n;
    c->kl = c->ku = 0;
    for (k = 0; k < n; k++) {
        int i = c->pat[k].row - NX, j = c->pat[k].col - NX;
        if (i < 0 || i >= NW || j < 0 || j >= NW) continue;
        if (i - j > c->kl) c->kl = i - j;
        if (j - i > c->ku) c->ku = j - i;
    }
    c->bw = 2 * c->kl + c->ku + 1;
    return 1;
}

/* --------------------------------------------- band LU of dg/dw, Newton */

#define AB(i, j) c->ab[(size_t)(i) * (size_t)c->bw + (size_t)((j) - (i) + c->kl)]

static int imin(int a, int b) { return a < b ? a : b; }
static int imax(int a, int b) { return a > b ? a : b; }

/* In-place LU with partial pivoting in band storage (interchanges in piv, the multipliers
 * of step k below the diagonal of column k); returns 0 if singular.  With a full band
 * these are the operations of a dense LU with partial pivoting. */
static int band_factor(Instance *c) {
    const int n = NW, kl = c->kl, up = c->kl + c->ku;
    int i, j, k, p;
    for (k = 0; k < n; k++) {
        const int last = imin(k + kl, n - 1), right = imin(k + up, n - 1);
        p = k;
        for (i = k + 1; i <= last; i++)
            if (fabs(AB(i, k)) > fabs(AB(p, k))) p = i;
        if (!(fabs(AB(p, k)) > 0.0) || !isfinite(AB(p, k))) return 0;
        c->piv[k] = p;
        if (p != k)
            for (j = k; j <= right; j++) {
                double tmp = AB(k, j); AB(k, j) = AB(p, j); AB(p, j) = tmp;
            }
        for (i = k + 1; i <= last; i++) {
            AB(i, k) /= AB(k, k);
            for (j = k + 1; j <= right; j++) AB(i, j) -= AB(i, k) * AB(k, j);
        }
    }
    return 1;
}

/* b := (dg/dw)^-1 b */
static void band_solve(const Instance *c, double b[]) {
    const int n = NW, kl = c->kl, up = c->kl + c->ku;
    int i, k;
    for (k = 0; k < n; k++) {
        const int last = imin(k + kl, n - 1);
        if (c->piv[k] != k) { double tmp = b[k]; b[k] = b[c->piv[k]]; b[c->piv[k]] = tmp; }
        for (i = k + 1; i <= last; i++) b[i] -= AB(i, k) * b[k];
    }
    for (i = n - 1; i >= 0; i--) {
        const int right = imin(i + up, n - 1);
        for (k = i + 1; k <= right; k++) b[i] -= AB(i, k) * b[k];
        b[i] /= AB(i, i);
    }
}

/* b := (dg/dw)^-T b */
static void band_solve_transposed(const Instance *c, double b[]) {
    const int n = NW, kl = c->kl, up = c->kl + c->ku;
    int i, k;
    for (i = 0; i < n; i++) {
        for (k = imax(0, i - up); k < i; k++) b[i] -= AB(k, i) * b[k];
        b[i] /= AB(i, i);
    }
    for (k = n - 1; k >= 0; k--) {
        const int last = imin(k + kl, n - 1);
        for (i = k + 1; i <= last; i++) b[k] -= AB(i, k) * b[i];
        if (c->piv[k] != k) { double tmp = b[k]; b[k] = b[c->piv[k]]; b[c->piv[k]] = tmp; }
    }
}

/* dg/dw from pval, factorised. */
static int factor_gw(Instance *c) {
    int k;
    memset(c->ab, 0, sizeof(double) * (size_t)NW * (size_t)c->bw);
    for (k = 0; k < c->nnz; k++) {
        int i = c->pat[k].row - NX, j = c->pat[k].col - NX;
        if (i >= 0 && i < NW && j >= 0 && j < NW) AB(i, j) += c->pval[k];
    }
    return band_factor(c);
}

static double norm2(int n, const double v[]) {
    double s = 0.0;
    int i;
    for (i = 0; i < n; i++) s += v[i] * v[i];
    return sqrt(s);
}

/* Damped Newton iteration for g(t, x, w, u) = 0, warm-started from w. */
static int solve_algebraic(Instance *c) {
    double *res = c->nres, *rt = c->rt, *wt = c->wt, *dw = c->dw;
    double rscale, rprev = INFINITY;
    int i, it, k;

    eval_solved(c, c->w, c->nder, res, c->ny);
    if (discard_reason) return 0;
    rscale = norm2(NW, res) > 1.0 ? norm2(NW, res) : 1.0;
    for (it = 0; it < 100; it++) {
        double r0 = norm2(NW, res), lam = 1.0, step = 0.0;
        if (r0 == 0.0) break;
        /* Rounding level: with an ill-conditioned dg/dw the step never falls below
         * 1e-12, but the residual stops falling; accept once it is 1e-10 of the start. */
        if (r0 <= 1e-10 * rscale && r0 > 0.25 * rprev) break;
        rprev = r0;
        partials_at(c, c->w);
        if (discard_reason) return 0;
        if (!factor_gw(c)) {
            logmsg(c, fmi3Error, "Newton: dg/dw is singular at t=%g", c->d.t);
            return 0;
        }
        for (i = 0; i < NW; i++) dw[i] = -res[i];
        band_solve(c, dw);
        for (k = 0; k <= 30; k++, lam *= 0.5) {  /* backtracking on |g| */
            if (k == 30) lam = 1.0;                /* no decrease: take the full step */
            for (i = 0; i < NW; i++) wt[i] = c->w[i] + lam * dw[i];
            eval_solved(c, wt, c->nder, rt, c->ny);
            if (discard_reason && k < 30) { discard_reason = NULL; continue; }
            if (k == 30 || norm2(NW, rt) <= (1.0 - 1e-4 * lam) * r0) break;
        }
        for (i = 0; i < NW; i++) {
            double s = fabs(lam * dw[i]) / fabs(MODEL.w_nominal[i]);
            if (s > step) step = s;
            c->w[i] = wt[i];
            res[i] = rt[i];
        }
        if (discard_reason || !(norm2(NW, res) < INFINITY)) break;
        if (step <= 1e-12) break;
    }
    if (discard_reason) return 0;
    if (it == 100 || !(norm2(NW, res) < INFINITY)) {
        logmsg(c, fmi3Error, "Newton: no convergence for g = 0 at t=%g", c->d.t);
        return 0;
    }
    c->d.w_consistent = 1;
    return 1;
}

/* Bring der, res, y (and w if the FMU computes it) up to date. */
static fmi3Status update(Instance *c) {
    Data *d = &c->d;
    discard_reason = NULL;
    if (!d->w_consistent && (d->state & RUNNING) && fmu_computes_w(c)) {
        if (NW > 0 && !solve_algebraic(c)) return discard_reason ? discarded(c) : fmi3Error;
        d->w_consistent = 1;
        d->eval_valid = 0;
    }
    if (!d->eval_valid) {
        eval_at(c, c->w, c->der, c->res, c->y);
#ifdef DEFECT_INDICATORS_STALE
        if (NZ > 0) indicators_at(c, c->wlast);   /* a cache keyed on t and x only */
        memcpy(c->wlast, c->w, sizeof(double) * (size_t)NW);
#else
        if (NZ > 0) indicators_at(c, c->w);
#endif
        if (discard_reason) return discarded(c);
        d->eval_valid = 1;
#ifdef DEFECT_SHARED
        c->partials_valid = 0;
#if DEFECT_SHARED == SHARED_VALUES
        if (SHARED_WRITES(c)) {
            memcpy(shared_values, c->der, sizeof(double) * (size_t)(NX + NW + NY));
            shared_set = 1;
        }
#endif
#endif
    }
#if defined(DEFECT_SHARED) && DEFECT_SHARED == SHARED_VALUES
    shared_read_values(c);   /* what every reader of the results then returns */
#endif
    return fmi3OK;
}

/* ----------------------------------------------------- partial derivatives */

/* Row of an unknown: der, res, y (the model's rows) or NROWS + i for w[i]; -1 if invalid. */
static int unknown_row(const Instance *c, fmi3ValueReference vr) {
    int i, kind = lookup(c, vr, &i);
    if (kind == K_DER) return i;
    if (kind == K_Y) return NX + NW + i;
    if (kind == K_RES && c->d.dae) return NX + i;
    if (kind == K_W && c->d.dae && c->d.state == InitializationMode) return NROWS + i;
    return -1;
}

/* Column of a known (x, w, u, t) or -1. */
static int known_col(const Instance *c, fmi3ValueReference vr) {
    int i, kind = lookup(c, vr, &i);
    if (kind == K_X) return i;
    if (kind == K_U) return NX + NW + i;
    if (kind == K_TIME) return NX + NW + NU;
    if (kind == K_W && !fmu_computes_w(c)) return NX + i;
#ifdef DEFECT_KNOWN_UNCHECKED
    if (kind != K_NONE && NX > 0) return 0;   /* any variable is taken as the first state */
#endif
#ifdef DEFECT_CRASH_ON_ILLEGAL_KNOWN
    if (kind == K_Y) { volatile double *nowhere = NULL; return (int)*nowhere; }   /* crash */
#endif
    return -1;
}

/* out := J s (all rows) */
static void jac_times(const Instance *c, const double s[], double out[]) {
    int k;
    memset(out, 0, sizeof(double) * (size_t)NROWS);
    for (k = 0; k < c->nnz; k++) out[c->pat[k].row] += c->pval[k] * s[c->pat[k].col];
}

/* out := J^T a (all columns) */
static void jac_transposed_times(const Instance *c, const double a[], double out[],
                                 int adjoint_defect) {
    int k;
    memset(out, 0, sizeof(double) * (size_t)NCOLS);
    for (k = 0; k < c->nnz; k++) {
        double e = c->pval[k];
#ifdef DEFECT_WRONG_ADJOINT
        if (adjoint_defect && c->pat[k].row == NX && c->pat[k].col == NX) e *= 2.0;
#else
        (void)adjoint_defect;
#endif
        out[c->pat[k].col] += e * a[c->pat[k].row];
    }
}

/*
 * Directional derivative: the partials J s or, where the FMU computes w, the total
 * derivative with dw/dk = -g_w^-1 g_k:  J_k s - J_w z with z = g_w^-1 (J s)_res, and -z
 * for the rows of w (Initialization Mode).  s has zeros in the w columns then.
 */
static void directional(Instance *c, int total) {
    int i;
    jac_times(c, c->s, c->v);
    if (!total) return;
    for (i = 0; i < NW; i++) c->z[i] = c->v[NX + i];
    band_solve(c, c->z);
    memset(c->s2, 0, sizeof(double) * (size_t)NCOLS);
    for (i = 0; i < NW; i++) c->s2[NX + i] = c->z[i];
    jac_times(c, c->s2, c->v2);
    for (i = 0; i < NROWS; i++) c->v[i] -= c->v2[i];
}

/*
 * Adjoint derivative: a^T J or, where the FMU computes w, a^T J_k - mu^T g_k with
 * g_w^T mu = J_w^T a + b (b: the seeds of the rows of w, held in z on entry).
 */
static void adjoint(Instance *c, int total) {
    int i;
    jac_transposed_times(c, c->a, c->p, !total);
    if (!total) return;
    for (i = 0; i < NW; i++) c->z[i] += c->p[NX + i];
    band_solve_transposed(c, c->z);
    memset(c->a2, 0, sizeof(double) * (size_t)NROWS);
    for (i = 0; i < NW; i++) c->a2[NX + i] = c->z[i];
    jac_transposed_times(c, c->a2, c->p2, 0);
    for (i = 0; i < NCOLS; i++) c->p[i] -= c->p2[i];
}

static fmi3Status partial_derivatives(fmi3Instance instance, const char *fn, int adj,
                                      const fmi3ValueReference unknowns[], size_t nU,
                                      const fmi3ValueReference knowns[], size_t nK,
                                      const fmi3Float64 seed[], size_t nSeed,
                                      fmi3Float64 sens[], size_t nSens) {
    size_t i, j;
    int total;
    fmi3Status status;
    BEGIN(fn, RUNNING);
#ifndef DEFECT_SEED_SIZE_UNCHECKED
    if (nSeed != (adj ? nU : nK) || nSens != (adj ? nK : nU))
        FAIL("%s: nSeed/nSensitivity do not match the numbers of knowns/unknowns", fn);
#endif
    if ((nU && !unknowns) || (nK && !knowns) || (nSeed && !seed) || (nSens && !sens))
        FAIL("%s: NULL argument", fn);
    for (i = 0; i < nU; i++)
        if (unknown_row(c, unknowns[i]) < 0)
            FAIL("%s: %u is not a valid unknown here", fn, (unsigned)unknowns[i]);
    for (j = 0; j < nK; j++)
        if (known_col(c, knowns[j]) < 0)
            FAIL("%s: %u is not a valid known here", fn, (unsigned)knowns[j]);
    if ((status = update(c)) != fmi3OK) return status;
#if defined(DEFECT_SHARED) && DEFECT_SHARED == SHARED_DERIVATIVES
    if (!c->partials_valid) {   /* computed once per point, kept in a global when written */
        partials_at(c, c->w);
        c->partials_valid = 1;
        if (SHARED_WRITES(c) && c->nnz > 0) {
            if (!shared_partials) shared_partials = (double *)malloc(sizeof(double) * (size_t)c->nnz);
            if (shared_partials) {
                memcpy(shared_partials, c->pval, sizeof(double) * (size_t)c->nnz);
                shared_set = 1;
            }
        }
    }
    if (shared_set && SHARED_READS(c) && shared_partials)
        memcpy(c->pval, shared_partials, sizeof(double) * (size_t)c->nnz);
#else
    partials_at(c, c->w);
#endif
    if (discard_reason) return discarded(c);
    total = fmu_computes_w(c) && NW > 0;
    if (total && !factor_gw(c)) FAIL("dg/dw is singular at t=%g", c->d.t);
    if (!adj) {
#ifdef DEFECT_ODE_DIRECTIONAL_OFF
        double off = 0.0;   /* ODE mode, Continuous-Time Mode: 10 % of d der(x[0])/d x[0] */
        if (!c->d.dae && c->d.state == ContinuousTimeMode && NX > 0) {
            memset(c->s, 0, sizeof(double) * (size_t)NCOLS);
            c->s[0] = 1.0;
            directional(c, total);
            off = 0.1 * c->v[0];
        }
#endif
        memset(c->s, 0, sizeof(double) * (size_t)NCOLS);
        for (j = 0; j < nK; j++) c->s[known_col(c, knowns[j])] += seed[j];
        directional(c, total);
        for (i = 0; i < nU; i++) {
            int r = unknown_row(c, unknowns[i]);
#ifdef DEFECT_INITIAL_DIRECTIONAL
            sens[i] = r < NROWS ? c->v[r] : c->z[r - NROWS];
#else
            sens[i] = r < NROWS ? c->v[r] : -c->z[r - NROWS];
#endif
#ifdef DEFECT_INITIAL_UNDECLARED
            if (c->d.state == InitializationMode && NX > 0 && NY > 0 && r == NX + NW)
                sens[i] += 0.25 * c->s[NX - 1];
#endif
#ifdef DEFECT_ODE_DIRECTIONAL_OFF
            if (r == 0) sens[i] += off * c->s[0];
#endif
        }
    } else {
        memset(c->a, 0, sizeof(double) * (size_t)NROWS);
        memset(c->z, 0, sizeof(double) * (size_t)NW);
        for (i = 0; i < nU; i++) {
            int r = unknown_row(c, unknowns[i]);
            if (r < NROWS) c->a[r] += seed[i];
            else           c->z[r - NROWS] += seed[i];   /* a row of w: -g_w^-1 g_k */
        }
        adjoint(c, total);
        for (j = 0; j < nK; j++) sens[j] = c->p[known_col(c, knowns[j])];
#ifdef DEFECT_INITIAL_UNDECLARED
        if (c->d.state == InitializationMode && NX > 0 && NY > 0)
            for (j = 0; j < nK; j++)
                if (known_col(c, knowns[j]) == NX - 1) sens[j] += 0.25 * c->a[NX + NW];
#endif
    }
    return fmi3OK;
}

/* ------------------------------------------------ per-element dependencies */

static int find_root(int parent[], int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
}

static int compare_pair(const void *pa, const void *pb) {
    const int *a = (const int *)pa, *b = (const int *)pb;
    if (a[0] != b[0]) return a[0] - b[0];
    return a[1] - b[1];
}

/*
 * What the per-element dependencies need besides the pattern: its entries by row, the
 * components of the graph linking the algebraic variables that share a residual, and the
 * knowns of each component's residuals (what every w of the component depends on in ODE
 * mode: structurally, solving g = 0 mixes them all).
 */
static int build_structure(Instance *c) {
    int *parent, *count, *pairs, npairs = 0, ncomp = 0, i, k, r;
    c->rowptr = (int *)grab(c, (size_t)NROWS + 1, sizeof(int));
    c->rowent = (int *)grab(c, (size_t)c->nnz, sizeof(int));
    c->comp = (int *)grab(c, (size_t)NW, sizeof(int));
    c->compptr = (int *)grab(c, (size_t)NW + 1, sizeof(int));
    c->colstamp = (int *)grab(c, (size_t)NCOLS, sizeof(int));
    c->compstamp = (int *)grab(c, (size_t)NW, sizeof(int));
    c->colkind = (fmi3DependencyKind *)grab(c, (size_t)NCOLS, sizeof(fmi3DependencyKind));
    c->depcol = (int *)grab(c, (size_t)NCOLS, sizeof(int));
    c->deps = (Dependency *)grab(c, (size_t)NCOLS, sizeof(Dependency));
    parent = (int *)calloc((size_t)NW + 1, sizeof(int));
    count = (int *)calloc((size_t)NROWS + 1, sizeof(int));
    pairs = (int *)calloc(2 * (size_t)c->nnz + 2, sizeof(int));
    if (c->alloc_failed || !parent || !count || !pairs) {
        free(parent); free(count); free(pairs);
        return 0;
    }
    for (k = 0; k < c->nnz; k++) c->rowptr[c->pat[k].row + 1]++;
    for (r = 0; r < NROWS; r++) c->rowptr[r + 1] += c->rowptr[r];
    for (k = 0; k < c->nnz; k++) {
        r = c->pat[k].row;
        c->rowent[c->rowptr[r] + count[r]++] = k;
    }
    for (i = 0; i < NW; i++) parent[i] = i;
    for (i = 0; i < NW; i++) {
        int first = -1;
        for (k = c->rowptr[NX + i]; k < c->rowptr[NX + i + 1]; k++) {
            int j = c->pat[c->rowent[k]].col - NX;
            if (j < 0 || j >= NW) continue;
            if (first < 0) first = j;
            else parent[find_root(parent, j)] = find_root(parent, first);
        }
    }
    for (i = 0; i < NW; i++) c->comp[i] = -1;
    for (i = 0; i < NW; i++) {
        int root = find_root(parent, i);
        if (c->comp[root] < 0) c->comp[root] = ncomp++;
        c->comp[i] = c->comp[root];
    }
    for (i = 0; i < NW; i++) {            /* (component, known column) of every residual */
        int first = -1;
        for (k = c->rowptr[NX + i]; k < c->rowptr[NX + i + 1] && first < 0; k++) {
            int j = c->pat[c->rowent[k]].col - NX;
            if (j >= 0 && j < NW) first = j;
        }
        if (first < 0) continue;          /* a residual without w determines none of them */
        for (k = c->rowptr[NX + i]; k < c->rowptr[NX + i + 1]; k++) {
            int col = c->pat[c->rowent[k]].col;
            if (col >= NX && col < NX + NW) continue;
            pairs[2 * npairs] = c->comp[first];
            pairs[2 * npairs + 1] = col;
            npairs++;
        }
    }
    qsort(pairs, (size_t)npairs, 2 * sizeof(int), compare_pair);
    c->compcol = (int *)grab(c, (size_t)npairs, sizeof(int));
    if (c->alloc_failed) {
        free(parent); free(count); free(pairs);
        return 0;
    }
    for (k = 0, i = 0; k < npairs; k++) {
        if (k > 0 && pairs[2 * k] == pairs[2 * k - 2] && pairs[2 * k + 1] == pairs[2 * k - 1])
            continue;
        c->compptr[pairs[2 * k] + 1]++;
        c->compcol[i++] = pairs[2 * k + 1];
    }
    for (k = 0; k < ncomp; k++) c->compptr[k + 1] += c->compptr[k];
    free(parent); free(count); free(pairs);
    return 1;
}

static fmi3ValueReference col_vr(int col) {
    if (col < NX) return MODEL.vr_x[col];
    if (col < NX + NW) return MODEL.vr_w[col - NX];
    if (col < NX + NW + NU) return MODEL.vr_u[col - NX - NW];
    return MODEL.vr_time;
}

static void add_known(Instance *c, int col, fmi3DependencyKind kind, int *m) {
    if (c->colstamp[col] != c->stamp) {
        c->colstamp[col] = c->stamp;
        c->colkind[col] = kind;
        c->depcol[(*m)++] = col;
    } else if (kind > c->colkind[col]) {
        c->colkind[col] = kind;          /* the less structured kind wins (enum order) */
    }
}

static void add_component(Instance *c, int comp, int *m) {
    int k;
    if (c->compstamp[comp] == c->stamp) return;
    c->compstamp[comp] = c->stamp;
    for (k = c->compptr[comp]; k < c->compptr[comp + 1]; k++)
        add_known(c, c->compcol[k], fmi3Dependent, m);
}

static int compare_dependency(const void *pa, const void *pb) {
    const Dependency *a = (const Dependency *)pa, *b = (const Dependency *)pb;
    return a->vr < b->vr ? -1 : a->vr > b->vr;
}

/*
 * The knowns `vr` depends on, into c->deps sorted by value reference; their number, or -1
 * if vr is no variable.  DAE mode after initialisation: the pattern (w are knowns, the
 * residuals unknowns).  ODE mode, and before fmi3ExitInitializationMode (the initial
 * dependencies, MS-13): through g = 0, a w stands for the knowns of its component.
 * Knowns, and residuals where g = 0 is solved (identically zero), depend on nothing.
 */
static int dependencies(Instance *c, fmi3ValueReference vr) {
    int i, k, m = 0, row = -1, kind = lookup(c, vr, &i);
    const int total = !c->d.dae || (c->d.state & BEFORE_INIT_EXIT);
    if (kind == K_NONE) return -1;
    c->stamp++;
    if (kind == K_DER) row = ROW_DER(i);
    else if (kind == K_Y) row = NX + NW + i;
    else if (kind == K_RES && !total) row = NX + i;
    else if (kind == K_W && total) add_component(c, c->comp[i], &m);
    if (row >= 0)
        for (k = c->rowptr[row]; k < c->rowptr[row + 1]; k++) {
            const ModelEntry *e = &c->pat[c->rowent[k]];
            if (total && e->col >= NX && e->col < NX + NW) add_component(c, c->comp[e->col - NX], &m);
            else add_known(c, e->col, e->kind, &m);
        }
    for (k = 0; k < m; k++) {
        c->deps[k].vr = col_vr(c->depcol[k]);
        c->deps[k].kind = c->colkind[c->depcol[k]];
    }
    qsort(c->deps, (size_t)m, sizeof *c->deps, compare_dependency);
    return m;
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                               size_t *n) {
    int m;
    BEGIN("fmi3GetNumberOfVariableDependencies", ANY_STATE);
    if (!MODEL.pattern) FAIL("fmi3GetNumberOfVariableDependencies: the model declares no pattern");
    if (!n) FAIL("fmi3GetNumberOfVariableDependencies: NULL argument");
    if ((m = dependencies(c, vr)) < 0)
        FAIL("fmi3GetNumberOfVariableDependencies: no variable %u", (unsigned)vr);
    *n = (size_t)m;
    return fmi3OK;
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
        size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
        size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[], size_t n) {
    int k, m;
    BEGIN("fmi3GetVariableDependencies", ANY_STATE);
    if (!MODEL.pattern) FAIL("fmi3GetVariableDependencies: the model declares no pattern");
    if ((m = dependencies(c, dependent)) < 0)
        FAIL("fmi3GetVariableDependencies: no variable %u", (unsigned)dependent);
    if (n != (size_t)m)
        FAIL("fmi3GetVariableDependencies: nDependencies is %u, not %d", (unsigned)n, m);
    if (m && (!elementIndicesOfDependent || !independents || !elementIndicesOfIndependents ||
              !dependencyKinds))
        FAIL("fmi3GetVariableDependencies: NULL argument");
    for (k = 0; k < m; k++) {
        elementIndicesOfDependent[k] = 0;     /* every variable is a scalar */
        independents[k] = c->deps[k].vr;
        elementIndicesOfIndependents[k] = 0;
        dependencyKinds[k] = c->deps[k].kind;
    }
    return fmi3OK;
}

/* --------------------------------------------------------------- set-up */

/* Every work array, sized from the model; 0 if memory ran out or the model is invalid. */
static int allocate(Instance *c) {
    const size_t rows = (size_t)NROWS, cols = (size_t)NCOLS, nw = (size_t)NW;
    c->vals = (double *)grab(c, (size_t)NVALUES, sizeof(double));
    c->index = (VrEntry *)grab(c, 2 + 2 * (size_t)NX + 2 * nw + (size_t)NU + (size_t)NY
                               + (size_t)NZ + (size_t)ND, sizeof(VrEntry));
    if (c->alloc_failed || !load_pattern(c)) return 0;
    c->x = c->vals;
    c->w = c->x + NX;
    c->u = c->w + NW;
    c->der = c->u + NU;
    c->res = c->der + NX;
    c->y = c->res + NW;
#ifdef DEFECT_GLOBAL_STATE
    c->x = global_x;
#endif
    c->ind = c->y + NY;
    c->disc = c->ind + NZ;
    build_index(c);
    c->pval = (double *)grab(c, (size_t)c->nnz, sizeof(double));
    c->ab = (double *)grab(c, nw * (size_t)c->bw, sizeof(double));
    c->piv = (int *)grab(c, nw, sizeof(int));
    c->s = (double *)grab(c, cols, sizeof(double));
    c->s2 = (double *)grab(c, cols, sizeof(double));
    c->p = (double *)grab(c, cols, sizeof(double));
    c->p2 = (double *)grab(c, cols, sizeof(double));
    c->v = (double *)grab(c, rows, sizeof(double));
    c->v2 = (double *)grab(c, rows, sizeof(double));
    c->a = (double *)grab(c, rows, sizeof(double));
    c->a2 = (double *)grab(c, rows, sizeof(double));
    c->z = (double *)grab(c, nw, sizeof(double));
    c->nres = (double *)grab(c, nw, sizeof(double));
    c->rt = (double *)grab(c, nw, sizeof(double));
    c->wt = (double *)grab(c, nw, sizeof(double));
    c->dw = (double *)grab(c, nw, sizeof(double));
    c->nder = (double *)grab(c, (size_t)NX, sizeof(double));
    c->ny = (double *)grab(c, (size_t)NY, sizeof(double));
    c->xsave = (double *)grab(c, (size_t)NX, sizeof(double));
    c->dsave = (double *)grab(c, (size_t)ND, sizeof(double));
#ifdef DEFECT_INDICATORS_STALE
    c->wlast = (double *)grab(c, nw, sizeof(double));
#endif
    if (c->alloc_failed) return 0;
    return !MODEL.pattern || build_structure(c);
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
#ifdef DEFECT_ZERO_DIRECTIONAL
    {
        fmi3Status status = partial_derivatives(instance, "fmi3GetDirectionalDerivative", 0,
            unknowns, nUnknowns, knowns, nKnowns, seed, nSeed, sensitivity, nSensitivity);
        size_t i;
        if (status == fmi3OK)   /* a stub that never computes anything */
            for (i = 0; i < nSensitivity; i++) sensitivity[i] = 0.0;
        return status;
    }
#else
    return partial_derivatives(instance, "fmi3GetDirectionalDerivative", 0, unknowns, nUnknowns,
                               knowns, nKnowns, seed, nSeed, sensitivity, nSensitivity);
#endif
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
    if (NX > NMAX || NW > NMAX || NU > NMAX || NY > NMAX || ND > NMAX || NZ > NMAX)
        return NULL;                                                  /* tables overflow */
    if (NZ < 0 || ND < 0 || (NZ > 0 && !MODEL.indicators)) {
        if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                                   "fmi3InstantiateModelExchange: event indicators without "
                                   "an indicators function");
        return NULL;
    }
    c = (Instance *)calloc(1, sizeof *c);
    if (!c) return NULL;
    c->name = (char *)malloc(strlen(instanceName) + 1);
    if (!c->name) { free(c); return NULL; }
    strcpy(c->name, instanceName);
    c->env = instanceEnvironment;
    c->logger = logMessage;
    c->logging = loggingOn;
    if (!allocate(c)) {
        logmsg(c, fmi3Error, "fmi3InstantiateModelExchange: cannot set up the model "
               "(out of memory or an invalid pattern)");
        fmi3FreeInstance(c);
        return NULL;
    }
    reset_data(c);
#ifdef DEFECT_STALE_STATES
    if (have_stale) memcpy(c->x, stale_x, sizeof(double) * (size_t)NX);
#endif
#ifdef DEFECT_SHARED
    c->ordinal = ++shared_created;
#endif
#ifdef DEFECT_LEAK_CALL
    leak("fmi3InstantiateModelExchange");
#endif
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
    int k;
    if (!c) return;
#ifdef DEFECT_LEAK_CALL
    leak("fmi3FreeInstance");
#endif
#ifdef DEFECT_STALE_STATES
    if (c->x) {
        memcpy(stale_x, c->x, sizeof(double) * (size_t)NX);
        have_stale = 1;
    }
#endif
    for (k = 0; k < c->nblocks; k++) free(c->blocks[k]);
    free(c->name);
    free(c);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
        fmi3Float64 tolerance, fmi3Float64 startTime, fmi3Boolean stopTimeDefined,
        fmi3Float64 stopTime) {
    BEGIN("fmi3EnterInitializationMode", Instantiated);
    (void)toleranceDefined; (void)tolerance;
    if (stopTimeDefined && stopTime < startTime) FAIL("stopTime < startTime");
#ifdef DEFECT_STOP_TIME_REFUSED
    if (stopTimeDefined) FAIL("fmi3EnterInitializationMode: a stop time is not supported");
#endif
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
        memcpy(c->w, MODEL.w_start, sizeof(double) * (size_t)NW);
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
#if defined(DEFECT_RESET_KEEPS_SWITCH) || defined(DEFECT_RESET_KEEPS_TIME) || \
    defined(DEFECT_RESET_KEEPS_GUESS) || defined(DEFECT_RESET_KEEPS_GUESS_DAE)
    {   /* what survives the reset: the DAE switch and the first state, time and the evaluation
           cache, or the algebraic variables (the defects combine) */
        Data kept = c->d;
        double x0 = NX > 0 ? c->x[0] : 0.0;
        memcpy(c->wt, c->w, sizeof(double) * (size_t)NW);
        reset_data(c);
        (void)kept; (void)x0;
#ifdef DEFECT_RESET_KEEPS_SWITCH
        c->d.dae = kept.dae;
        if (NX > 0) c->x[0] = x0;
#ifdef DEFECT_W_START_DAE
        if (c->d.dae) c->w[0] = MODEL.w_start[0] + 0.5;   /* DAE mode's start, as on the switch */
#endif
#endif
#ifdef DEFECT_RESET_KEEPS_TIME
        c->d.t = kept.t;
        c->d.eval_valid = kept.eval_valid;
#endif
#ifdef DEFECT_RESET_KEEPS_GUESS
        memcpy(c->w, c->wt, sizeof(double) * (size_t)NW);
#endif
#ifdef DEFECT_RESET_KEEPS_GUESS_DAE
        c->guess_kept = 1;
#endif
        return fmi3OK;
    }
#endif
    reset_data(c);
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
    fmi3Status status;
    BEGIN("fmi3GetFloat64", ANY_STATE);
    if (nvr != nValues) FAIL("fmi3GetFloat64: nValues != nValueReferences");
    if (nvr && (!vr || !values)) FAIL("fmi3GetFloat64: NULL argument");
    for (k = 0; k < nvr; k++) {
        int kind = lookup(c, vr[k], &idx);
        if (!slot(c, kind, idx)) FAIL("fmi3GetFloat64: no Float64 variable %u", (unsigned)vr[k]);
#ifdef DEFECT_GET_REFUSED
        if (READ_AIMED(c, kind))
            FAIL("fmi3GetFloat64: variable %u cannot be read in %s", (unsigned)vr[k],
                 state_name(c->d.state));
#endif
#ifdef DEFECT_STALE_READ
        if (kind == READ_KIND && READ_MODE(c)) continue;   /* read alone: the last point's value */
#endif
        computed |= kind == K_DER || kind == K_RES || kind == K_Y || kind == K_W || kind == K_Z;
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
    if (computed && (status = update(c)) != fmi3OK) return status;
    for (k = 0; k < nvr; k++) {
        int kind = lookup(c, vr[k], &idx);
#ifdef DEFECT_GET_UNWRITTEN
        if (READ_AIMED(c, kind)) continue;                /* values[k] left as the caller had it */
#endif
        values[k] = *slot(c, kind, idx);
#ifdef DEFECT_GET_NAN
        if (READ_AIMED(c, kind)) values[k] = NAN;
#endif
#ifdef DEFECT_INITIAL_UNDECLARED
        /* only as read in Initialization Mode: the stored y[0] is untouched */
        if (kind == K_Y && idx == 0 && c->d.state == InitializationMode && NX > 0)
            values[k] += 0.25 * c->x[NX - 1];
#endif
    }
    return fmi3OK;
}

static int may_set(const Instance *c, int kind) {
    const Data *d = &c->d;
    const int running = InitializationMode | EventMode | ContinuousTimeMode;
    switch (kind) {
#ifdef DEFECT_STATE_SET_REFUSED
    case K_X: return (d->state & (Instantiated | InitializationMode | EventMode)) != 0;
#else
    case K_X:
#endif
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
        int kind = lookup(c, vr[k], &idx);
        if (!slot(c, kind, idx)) FAIL("fmi3SetFloat64: no Float64 variable %u", (unsigned)vr[k]);
        if (!may_set(c, kind))
            FAIL("fmi3SetFloat64: variable %u cannot be set in %s%s", (unsigned)vr[k],
                 state_name(c->d.state), kind == K_W && !c->d.dae ? " (ODE mode)" : "");
#ifdef DEFECT_INPUT_NOT_SETTABLE
        if (kind == K_U && c->d.dae && c->d.state == ContinuousTimeMode) {
            c->d.state = Terminated;   /* after fmi3Error only Terminated is left (SM-04) */
            FAIL("fmi3SetFloat64: input %u cannot be set in DAE mode", (unsigned)vr[k]);
        }
#endif
    }
    for (k = 0; k < nvr; k++) {
        int kind = lookup(c, vr[k], &idx);
#ifdef DEFECT_STATE_SET_IGNORED
        if (kind == K_X && c->d.state == ContinuousTimeMode) continue;   /* "accepted" */
#endif
        *slot(c, kind, idx) = values[k];
#if defined(DEFECT_SHARED) && DEFECT_SHARED == SHARED_INPUTS
        if (kind == K_U && SHARED_WRITES(c)) {
            memcpy(shared_u, c->u, sizeof(double) * (size_t)NU);
            shared_set = 1;
        }
#endif
    }
#if defined(DEFECT_SET_KEEPS_CACHE) && KEEPS_CACHE_ON == 3
    if (READ_MODE(c) && c->d.state == ContinuousTimeMode) return fmi3OK;
#endif
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
        if (lookup(c, vr[k], &idx) != K_ENABLE) FAIL("fmi3GetBoolean: no Boolean variable %u", (unsigned)vr[k]);
    for (k = 0; k < nvr; k++) values[k] = c->d.dae;
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues) {
    size_t k;
    int idx;
    BEGIN("fmi3SetBoolean", ANY_STATE);
    if (nvr != nValues) FAIL("fmi3SetBoolean: nValues != nValueReferences");
#ifndef DEFECT_SETBOOLEAN_ANY_VR
    for (k = 0; k < nvr; k++)
        if (lookup(c, vr[k], &idx) != K_ENABLE) FAIL("fmi3SetBoolean: no Boolean variable %u", (unsigned)vr[k]);
#else
    (void)idx;
#endif
    if (nvr && !(c->d.state == ConfigurationMode ||
                 (c->d.state == ReconfigurationMode && MODEL.enable_tunable)))
        FAIL("fmi3SetBoolean: the structural parameter %u cannot be set in %s",
             (unsigned)MODEL.vr_enable, state_name(c->d.state));
    for (k = 0; k < nvr; k++) c->d.dae = values[k] ? fmi3True : fmi3False;
#ifdef DEFECT_W_START_DAE
    /* the DAE mode's algebraic variables start elsewhere than the XML says (a binary that sets
       them when the mode is chosen, as ODE mode computes them when read) */
    if (nvr && c->d.dae && c->d.state == ConfigurationMode) c->w[0] = MODEL.w_start[0] + 0.5;
#endif
#ifdef DEFECT_RESET_KEEPS_GUESS_DAE
    /* the guess kept across fmi3Reset comes back when DAE mode is switched on again */
    if (nvr && c->d.dae && c->guess_kept) {
        memcpy(c->w, c->wt, sizeof(double) * (size_t)NW);
        c->guess_kept = 0;
    }
#endif
#if defined(DEFECT_SHARED) && DEFECT_SHARED == SHARED_MODE
    if (nvr && SHARED_WRITES(c)) {
        shared_dae = c->d.dae;
        shared_set = 1;
    }
#endif
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
    ModelEvent ev;
    int i, d_changed = 0, x_changed = 0;
    fmi3Status status;
    BEGIN("fmi3UpdateDiscreteStates", EventMode);
    memset(&ev, 0, sizeof ev);
#ifdef DEFECT_EVENT_OUTPUTS_UNWRITTEN
    (void)i; (void)d_changed; (void)x_changed; (void)status;
    (void)discreteStatesNeedUpdate; (void)terminateSimulation; (void)nextEventTime;
    (void)nominalsOfContinuousStatesChanged; (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined;
    return fmi3OK;   /* a stub: no event is handled and no output argument written */
#endif
    if (MODEL.event) {
        /* the hook sees the w the FMU solved (ODE mode) or the importer set (DAE mode) */
        if ((status = update(c)) != fmi3OK) return status;
        memcpy(c->xsave, c->x, sizeof(double) * (size_t)NX);
        memcpy(c->dsave, c->disc, sizeof(double) * (size_t)ND);
        MODEL.event(c->d.t, c->x, c->w, c->u, c->disc, &ev);
        for (i = 0; i < ND; i++) d_changed |= c->disc[i] != c->dsave[i];
        for (i = 0; i < NX; i++) x_changed |= c->x[i] != c->xsave[i];
#ifdef DEFECT_EVENT_STALE
        d_changed = 0;   /* the change of d goes unnoticed: no update, no fresh evaluation */
#endif
        if (d_changed || x_changed) {
            changed(&c->d);
            logmsg(c, fmi3OK, "t=%g: event%s%s", c->d.t, d_changed ? ", discrete variables "
                   "changed" : "", x_changed ? ", states re-initialised" : "");
        }
    }
#ifdef DEFECT_STATES_CHANGED_SPURIOUS
    x_changed = 1;   /* "the states changed" at every event */
#endif
#ifdef DEFECT_NEXT_EVENT_PAST
    if (!ev.next_time_defined) {   /* an event "at" a time already passed */
        ev.next_time_defined = fmi3True;
        ev.next_time = c->d.t - (DEFECT_NEXT_EVENT_PAST);
    }
#endif
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = d_changed ? fmi3True : fmi3False;
    if (terminateSimulation) *terminateSimulation = ev.terminate ? fmi3True : fmi3False;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
    if (valuesOfContinuousStatesChanged)
        *valuesOfContinuousStatesChanged = x_changed ? fmi3True : fmi3False;
    if (nextEventTimeDefined)
        *nextEventTimeDefined = ev.next_time_defined ? fmi3True : fmi3False;
    if (nextEventTime) *nextEventTime = ev.next_time_defined ? ev.next_time : 0.0;
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
#if defined(DEFECT_SET_KEEPS_CACHE) && KEEPS_CACHE_ON == 1
    if (READ_MODE(c)) return fmi3OK;   /* the cache is keyed on the states only */
#endif
    changed(&c->d);
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t nx) {
    BEGIN("fmi3SetContinuousStates", ContinuousTimeMode);
    if (nx != (size_t)NX || (nx && !x)) FAIL("fmi3SetContinuousStates: expected %d states", NX);
    memcpy(c->x, x, nx * sizeof(double));
#if defined(DEFECT_SET_KEEPS_CACHE) && KEEPS_CACHE_ON == 2
    if (READ_MODE(c)) return fmi3OK;
#endif
    changed(&c->d);
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 der[], size_t nx) {
    fmi3Status status;
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
    if ((status = update(c)) != fmi3OK) return status;
    memcpy(der, c->der, nx * sizeof(double));
#ifdef DEFECT_VECTOR_DERIVATIVES
    if (nx && READ_MODE(c)) der[nx - 1] += 1e-6 * (1.0 + fabs(der[nx - 1]));
#endif
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t nx) {
    BEGIN("fmi3GetContinuousStates", RUNNING);
    if (nx != (size_t)NX || (nx && !x)) FAIL("fmi3GetContinuousStates: expected %d states", NX);
    memcpy(x, c->x, nx * sizeof(double));
#ifdef DEFECT_VECTOR_STATES
    if (nx && READ_MODE(c)) x[nx - 1] += 1e-6 * (1.0 + fabs(x[nx - 1]));
#endif
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nx) {
    BEGIN("fmi3GetNominalsOfContinuousStates", Instantiated | RUNNING);
    if (nx != (size_t)NX || (nx && !nominals)) FAIL("fmi3GetNominalsOfContinuousStates: expected %d", NX);
#ifdef DEFECT_NOMINAL_UNWRITTEN
    if (nx) { memcpy(nominals + 1, MODEL.x_nominal + 1, (nx - 1) * sizeof(double)); return fmi3OK; }
#endif
    memcpy(nominals, MODEL.x_nominal, nx * sizeof(double));
#ifdef DEFECT_NOMINAL_INVALID
#ifndef NOMINAL_VALUE
#define NOMINAL_VALUE 0.0
#endif
    if (nx && READ_MODE(c)) nominals[0] = NOMINAL_VALUE;
#endif
#ifdef DEFECT_NOMINAL_NOT_XML
    if (nx && READ_MODE(c)) nominals[0] *= 1.1;   /* the binary's own nominal, not the XML's */
#endif
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 z[], size_t nz) {
    fmi3Status status;
    BEGIN("fmi3GetEventIndicators", RUNNING);
    if (nz != (size_t)NZ || (nz && !z)) {
        if (NZ == 0) FAIL("fmi3GetEventIndicators: the model has no event indicators");
        FAIL("fmi3GetEventIndicators: expected %d event indicators", NZ);
    }
    if (nz == 0) return fmi3OK;
    if ((status = update(c)) != fmi3OK) return status;
    memcpy(z, c->ind, nz * sizeof(double));
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) {
    BEGIN("fmi3GetNumberOfEventIndicators", NOT_CONFIG);
    if (!n) FAIL("fmi3GetNumberOfEventIndicators: NULL argument");
#ifdef DEFECT_INDICATOR_COUNT
    *n = (size_t)NZ + 1;   /* counts a removed indicator still */
#else
    *n = (size_t)NZ;
#endif
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
    if (!*state &&
        !(*state = malloc(sizeof(SavedState) + sizeof(double) * (size_t)NVALUES)))
        FAIL("fmi3GetFMUState: out of memory");
    ((SavedState *)*state)->d = c->d;
    memcpy(((SavedState *)*state)->vals, c->vals, sizeof(double) * (size_t)NVALUES);
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState state) {
    BEGIN("fmi3SetFMUState", NOT_CONFIG);
    if (!state) FAIL("fmi3SetFMUState: NULL state");
    c->d = ((const SavedState *)state)->d;
    memcpy(c->vals, ((const SavedState *)state)->vals, sizeof(double) * (size_t)NVALUES);
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
