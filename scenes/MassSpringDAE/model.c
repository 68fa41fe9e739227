/*
 * MassSpringDAE - a mass on a spring, the spring force an algebraic variable:
 *
 *   der(p) = v
 *   der(v) = f / m
 *        0 = f + k*p                      (springForce)
 *   energy = m*v^2/2 + k*p^2/2            (an output: constant along every solution)
 *
 * m = 2 kg, k = 8 N/m: p = cos(2t), v = -2 sin(2t), energy = 4 J from p = 1, v = 0. The
 * energy is what a manifest's <Invariant> names (the working group's "ODE with invariants"
 * text, not part of 1.0.0-alpha.1): its variants add the element (tests/fixtures/defects/).
 *
 * DEFECT_ENERGY_DRIFT: der(p) = 1.05*v, so that d(energy)/dt = 0.05*k*p*v is not zero: the
 * energy drifts along the trajectory in both modes (by a few per cent over a period), while
 * every dependency and dependenciesKind stays true.
 */
#include "dae_model.h"

#define NX 2
#define NW 1
#define NU 0
#define NY 1

#define MASS 2.0
#define STIFFNESS 8.0

#ifdef DEFECT_ENERGY_DRIFT
#define GAIN 1.05
#else
#define GAIN 1.0
#endif

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    (void)t; (void)u;
    der[0] = GAIN * x[1];
    der[1] = w[0] / MASS;
    res[0] = w[0] + STIFFNESS * x[0];
    y[0] = 0.5 * MASS * x[1] * x[1] + 0.5 * STIFFNESS * x[0] * x[0];
}

static void partials(double t, const double x[], const double w[], const double u[],
                     double J[]) {
    (void)t; (void)w; (void)u;
    D_DER_X(0, 1) = GAIN;
    D_DER_W(1, 0) = 1.0 / MASS;
    D_RES_X(0, 0) = STIFFNESS;
    D_RES_W(0, 0) = 1.0;
    D_OUT_X(0, 0) = STIFFNESS * x[0];
    D_OUT_X(0, 1) = MASS * x[1];
}

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 1, .enable_tunable = fmi3False,
    .vr_x = {2, 4}, .vr_der = {3, 5},
    .vr_w = {6},    .vr_res = {7},
    .vr_y = {8},
    .x_start = {1.0, 0.0}, .w_start = {0.0},
    .x_nominal = {1.0, 1.0}, .w_nominal = {1.0},
    .eval = eval, .partials = partials,
};
