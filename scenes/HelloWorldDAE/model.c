/*
 * HelloWorldDAE - the tiny linear model of draft-shapes.md.
 *
 *   der(x) = y
 *        0 = y + 2*z - x        (g1)
 *        0 = y - 3*z - 2*x      (g2)
 *
 * Solution: z = -x/5, y = 7x/5, so der(x) = 1.4*x in ODE mode.
 */
#include "dae_model.h"

#ifdef DEFECT_NAN_DERIVATIVE
#include <math.h>
#endif

#define NX 1
#define NW 2
#define NU 0
#define NY 0

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    (void)t; (void)u; (void)y;
    der[0] = w[0];
#ifdef DEFECT_NAN_DERIVATIVE
    if (t > 0) der[0] = NAN;   /* a term undefined once time has advanced */
#endif
    res[0] = w[0] + 2 * w[1] - x[0];
    res[1] = w[0] - 3 * w[1] - 2 * x[0];
}

static void partials(double t, const double x[], const double w[], const double u[],
                     double J[]) {
    (void)t; (void)x; (void)w; (void)u;
    D_DER_W(0, 0) = 1;

    D_RES_X(0, 0) = -1;
    D_RES_W(0, 0) = 1;
    D_RES_W(0, 1) = 2;

    D_RES_X(1, 0) = -2;
    D_RES_W(1, 0) = 1;
    D_RES_W(1, 1) = -3;
}

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 1, .enable_tunable = fmi3False,
    .vr_x   = {2},      .vr_der = {3},
    .vr_w   = {4, 5},   .vr_res = {6, 7},
    .x_start = {1.0}, .w_start = {0.0, 0.0},
    .x_nominal = {1.0}, .w_nominal = {1.0, 1.0},
    .eval = eval, .partials = partials,
};
