/*
 * NearSingular - two algebraic equations that become the same equation as
 * eps -> 0 (compile with -DNEAR_SINGULAR_EPS=<value>; default 1e-3):
 *
 *   der(x) = -sin(z1 + 2*z2)
 *        0 = z1 + 2*z2 - x                                  (r1)
 *        0 = z1 + (2 + eps)*z2 - x - eps*sin(x)             (r2)
 *
 * The solution does not depend on eps: z2 = sin(x), z1 = x - 2*sin(x), so
 * der(x) = -sin(x).  dg/dw = [[1, 2], [1, 2 + eps]] has determinant eps and a
 * 2-norm condition number of about 10/eps; its near-null direction (2, -1)
 * leaves z1 + 2*z2, the only combination der(x) reads, unchanged, so the lost
 * digits of w do not reach the derivatives.
 */
#include <math.h>

#include "dae_model.h"

#ifndef NEAR_SINGULAR_EPS
#define NEAR_SINGULAR_EPS 1e-3
#endif

#define NX 1
#define NW 2
#define NU 0
#define NY 0

static const double EPS = NEAR_SINGULAR_EPS;

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    const double z1 = w[0], z2 = w[1];
    (void)t; (void)u; (void)y;
    der[0] = -sin(z1 + 2.0 * z2);
    res[0] = z1 + 2.0 * z2 - x[0];
    res[1] = z1 + (2.0 + EPS) * z2 - x[0] - EPS * sin(x[0]);
}

static void partials(double t, const double x[], const double w[], const double u[],
                     double J[]) {
    const double c = cos(w[0] + 2.0 * w[1]);
    (void)t; (void)u;
    D_DER_W(0, 0) = -c;
    D_DER_W(0, 1) = -2.0 * c;
    D_RES_X(0, 0) = -1.0;
    D_RES_W(0, 0) = 1.0;
    D_RES_W(0, 1) = 2.0;
    D_RES_X(1, 0) = -1.0 - EPS * cos(x[0]);
    D_RES_W(1, 0) = 1.0;
    D_RES_W(1, 1) = 2.0 + EPS;
}

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 1, .enable_tunable = fmi3False,
    .vr_x   = {2},      .vr_der = {3},
    .vr_w   = {4, 5},   .vr_res = {6, 7},
    .x_start = {1.0},   .w_start = {0.0, 0.0},
    .x_nominal = {1.0}, .w_nominal = {1.0, 1.0},
    .eval = eval, .partials = partials,
};
