/*
 * dae_model.h - the interface between the lsdae test-scene framework
 * (fmi3_framework.c) and one model file (scenes/<Name>/model.c).
 *
 * A model is a semi-explicit index-1 DAE
 *
 *     der(x) = f(t, x, w, u)      (derivatives)
 *          0 = g(t, x, w, u)      (residuals, one per algebraic variable)
 *          y = h(t, x, w, u)      (outputs)
 *
 * The model file defines exactly one object, `const ModelDef MODEL`, which
 * lists the value references of every variable, the start and nominal values
 * and two callbacks: `eval` (f, g, h) and `partials` (their analytic partial
 * derivatives, dense), or instead of `partials` the pair `pattern` / `partials_sparse`
 * (the same derivatives, only the structural nonzeros).  Everything else (state machine, Newton solver for ODE mode,
 * total derivatives, directional/adjoint derivatives) is in the framework.
 *
 * Optionally (all zero / NULL by default, so a model without events compiles unchanged) a
 * model has discrete variables d, event indicators z and an event hook; see "Events" below.
 *
 * Deliberately defective variants are built by compiling with -DDEFECT_xxx;
 * put the defect into model.c (or the framework) inside #ifdef DEFECT_xxx.
 */
#ifndef DAE_MODEL_H
#define DAE_MODEL_H

#include "fmi3Functions.h"

/* A scene may give its own defaults in scene_config.h (in its folder, which is on the include
 * path of both the framework and the model): e.g. a larger FMU_MAX_VARS for its default size. */
#if defined(__has_include)
#if __has_include("scene_config.h")
#include "scene_config.h"
#endif
#endif

/* Capacity of the value-reference, start and nominal tables of ModelDef below, i.e. the
 * largest nx, nw, nu, ny, nd, nz; a scalable scene (Chain) raises it with -DFMU_MAX_VARS=....
 * The framework sizes its own work arrays from nx, nw, nu, ny and keeps them on the heap. */
#ifndef FMU_MAX_VARS
#define FMU_MAX_VARS 8
#endif

typedef void (*ModelEvalFn)(double t, const double x[], const double w[],
                            const double u[], double der[], double res[],
                            double y[]);

/*
 * Partial derivatives.  J is a dense, row-major matrix, zeroed by the caller,
 * with the rows    [ der(0..nx-1) | res(0..nw-1) | y(0..ny-1) ]
 * and the columns  [ x(0..nx-1) | w(0..nw-1) | u(0..nu-1) | t ].
 * Use the D_* macros below to address it.
 */
typedef void (*ModelPartialsFn)(double t, const double x[], const double w[],
                                const double u[], double J[]);

/*
 * Optional sparse interface (for large models; the dense `partials` above keeps working).
 *
 * `pattern(entries)` lists the structural nonzeros of the same matrix: called once per
 * instance with NULL, it returns their number nnz; called again with an array of nnz
 * entries, it fills it (and returns nnz again).  Rows and columns are those of the D_*
 * macros (use ROW_* and COL_* below); an entry may appear more than once (values add up).
 * `kind` is what the unknown's `dependenciesKind` says about that known in DAE mode
 * (fmi3Constant, fmi3Fixed, ...; fmi3Independent, the value an initializer leaves out, is
 * read as fmi3Dependent).  `partials_sparse(t, x, w, u, values)` writes the nnz values in
 * the order of the pattern (the framework zeroes `values` first).
 *
 * With a pattern the framework works in O(nnz): directional and adjoint derivatives are
 * sparse products, dg/dw is factorised as a band matrix whose bandwidth comes from the
 * pattern (LU with partial pivoting; keep the algebraic variables ordered so that dg/dw is
 * banded), and fmi3GetNumberOfVariableDependencies / fmi3GetVariableDependencies report
 * the pattern (DAE mode) or the dependencies it implies through g = 0 (ODE mode, and
 * before fmi3ExitInitializationMode), so the XML can declare
 * providesPerElementDependencies="true".  Without a pattern every entry is structural:
 * dense products and a dense LU, and no per-element dependencies.
 */
typedef struct {
    int row;                  /* [ der | res | y ] */
    int col;                  /* [ x | w | u | t ] */
    fmi3DependencyKind kind;
} ModelEntry;

typedef int (*ModelPatternFn)(ModelEntry entries[]);
typedef void (*ModelPartialsSparseFn)(double t, const double x[], const double w[],
                                      const double u[], double values[]);

/*
 * Events (optional).
 *
 * d are discrete Float64 variables (causality local, variability discrete, initial
 * calculated): the FMU changes them, only in fmi3UpdateDiscreteStates; they start at d_start
 * (and again after fmi3Reset), are saved with the FMU state, are read with fmi3GetFloat64 and
 * cannot be set.  A model whose equations use d gives `eval_discrete` / `partials_discrete`
 * (eval / partials with d as an extra argument) instead of `eval` / `partials`; d is never a
 * known of the partial derivatives.
 *
 * z are the event indicators (Float64 variables, causality local or output, variability
 * continuous, listed as <EventIndicator> in the ModelStructure, in the order of vr_z).
 * `indicators` computes them from (t, x, w, u, d): in ODE mode from the w the FMU solved, in
 * DAE mode from the w the importer set.  fmi3GetEventIndicators returns them in
 * Initialization, Event and Continuous-Time Mode (and Terminated); fmi3GetFloat64 of vr_z[i]
 * gives the same values.
 *
 * `event` (optional) runs in every fmi3UpdateDiscreteStates: it may change d (a mode flag the
 * residuals use, so a state event can change a residual), and x (a re-initialisation), ask
 * to end the simulation, and announce the next time event.  The framework compares d and x
 * before and after the call: a change of d makes fmi3UpdateDiscreteStates report
 * discreteStatesNeedUpdate (the importer calls it again; the hook must reach a fixed point),
 * a change of x valuesOfContinuousStatesChanged; in ODE mode w is then solved again.  Within
 * the hook, w is the FMU's solved w (ODE mode) or the importer's (DAE mode).
 */
typedef void (*ModelEvalDiscreteFn)(double t, const double x[], const double w[],
                                    const double u[], const double d[], double der[],
                                    double res[], double y[]);
typedef void (*ModelPartialsDiscreteFn)(double t, const double x[], const double w[],
                                        const double u[], const double d[], double J[]);
typedef void (*ModelIndicatorsFn)(double t, const double x[], const double w[],
                                  const double u[], const double d[], double z[]);

typedef struct {
    fmi3Boolean terminate;          /* end the simulation (terminateSimulation) */
    fmi3Boolean next_time_defined;  /* a time event is due at next_time */
    double      next_time;
} ModelEvent;                       /* zeroed by the framework before each call */

typedef void (*ModelEventFn)(double t, double x[], const double w[], const double u[],
                             double d[], ModelEvent *event);

typedef struct {
    int nx;  /* continuous states x (and their derivatives) */
    int nw;  /* algebraic variables w; also the number of residuals */
    int nu;  /* continuous inputs u */
    int ny;  /* continuous outputs y */

    fmi3ValueReference vr_time;       /* the independent variable */
    fmi3ValueReference vr_enable;     /* Boolean structural parameter (DAE mode switch) */
    fmi3Boolean        enable_tunable;/* variability tunable (else fixed) */

    fmi3ValueReference vr_x[FMU_MAX_VARS];
    fmi3ValueReference vr_der[FMU_MAX_VARS];
    fmi3ValueReference vr_w[FMU_MAX_VARS];
    fmi3ValueReference vr_res[FMU_MAX_VARS];
    fmi3ValueReference vr_u[FMU_MAX_VARS];
    fmi3ValueReference vr_y[FMU_MAX_VARS];

    double x_start[FMU_MAX_VARS];
    double w_start[FMU_MAX_VARS];     /* the guess values (initial="approx") */
    double u_start[FMU_MAX_VARS];
    double x_nominal[FMU_MAX_VARS];
    double w_nominal[FMU_MAX_VARS];   /* used to scale the Newton step */

    ModelEvalFn     eval;
    ModelPartialsFn partials;                 /* dense; or NULL with the two below */

    ModelPatternFn        pattern;            /* optional: the sparse interface above */
    ModelPartialsSparseFn partials_sparse;

    /* Events (optional, see "Events" above; a dense model only) */
    int nd;                                   /* discrete variables d */
    int nz;                                   /* event indicators z */
    fmi3ValueReference vr_d[FMU_MAX_VARS];
    fmi3ValueReference vr_z[FMU_MAX_VARS];
    double d_start[FMU_MAX_VARS];
    ModelEvalDiscreteFn     eval_discrete;    /* replaces eval when set */
    ModelPartialsDiscreteFn partials_discrete;/* replaces partials when set */
    ModelIndicatorsFn       indicators;       /* required when nz > 0 */
    ModelEventFn            event;            /* run in fmi3UpdateDiscreteStates */
} ModelDef;

extern const ModelDef MODEL;

/*
 * Called by a model's eval or partials when it cannot be evaluated at the point
 * it was given (e.g. the square root of a state that has become negative).  The
 * framework then returns fmi3Discard from the FMI call that needed the values
 * (the importer is expected to retry with a smaller step); the callback should
 * still fill its outputs (NaN is fine).  `reason` is a static string for the log.
 */
void model_discard(const char *reason);

/*
 * Helpers for model.c.  They need the model's sizes as the macros NX, NW, NU
 * (define them before use) and a local matrix called J.
 */
#define D_NCOLS        (NX + NW + NU + 1)
#define D_AT(r, c)     J[(r) * D_NCOLS + (c)]
#define D_DER_X(i, j)  D_AT((i),           (j))
#define D_DER_W(i, j)  D_AT((i),           NX + (j))
#define D_DER_U(i, j)  D_AT((i),           NX + NW + (j))
#define D_DER_T(i)     D_AT((i),           NX + NW + NU)
#define D_RES_X(i, j)  D_AT(NX + (i),      (j))
#define D_RES_W(i, j)  D_AT(NX + (i),      NX + (j))
#define D_RES_U(i, j)  D_AT(NX + (i),      NX + NW + (j))
#define D_RES_T(i)     D_AT(NX + (i),      NX + NW + NU)
#define D_OUT_X(i, j)  D_AT(NX + NW + (i), (j))
#define D_OUT_W(i, j)  D_AT(NX + NW + (i), NX + (j))
#define D_OUT_U(i, j)  D_AT(NX + NW + (i), NX + NW + (j))
#define D_OUT_T(i)     D_AT(NX + NW + (i), NX + NW + NU)

/* Rows and columns for ModelEntry (same NX, NW, NU macros). */
#define ROW_DER(i)     (i)
#define ROW_RES(i)     (NX + (i))
#define ROW_OUT(i)     (NX + NW + (i))
#define COL_X(j)       (j)
#define COL_W(j)       (NX + (j))
#define COL_U(j)       (NX + NW + (j))
#define COL_T          (NX + NW + NU)

#endif /* DAE_MODEL_H */
