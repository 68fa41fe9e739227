/*
 * VanDerPolDAE - the van der Pol oscillator in its DAE limit (mu -> infinity,
 * the slow motion on the critical manifold), started at y1 = 2:
 *
 *   der(y1) = y2
 *         0 = (1 - y1^2)*y2 - y1                            (residual)
 *
 * dg/dy2 = 1 - y1^2 vanishes at y1 = 1, which the solution reaches at
 * t* = 1.5 - ln 2 = 0.806853 (integrate (1 - y1^2)/y1 dy1 = dt from 2 to 1):
 * an impasse point, where y2 = y1/(1 - y1^2) and der(y1) grow without bound
 * and no index-1 solver can continue.  The model is regular everywhere else.
 */
#include "dae_model.h"

#define NX 1
#define NW 1
#define NU 0
#define NY 0

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    const double y1 = x[0], y2 = w[0];
    (void)t; (void)u; (void)y;
    der[0] = y2;
    res[0] = (1.0 - y1 * y1) * y2 - y1;
}

static void partials(double t, const double x[], const double w[], const double u[],
                     double J[]) {
    const double y1 = x[0], y2 = w[0];
    (void)t; (void)u;
    D_DER_W(0, 0) = 1.0;
    D_RES_X(0, 0) = -2.0 * y1 * y2 - 1.0;
    D_RES_W(0, 0) = 1.0 - y1 * y1;
}

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 1, .enable_tunable = fmi3False,
    .vr_x   = {2},   .vr_der = {3},
    .vr_w   = {4},   .vr_res = {5},
    .x_start = {2.0}, .w_start = {-0.5},
    .x_nominal = {1.0}, .w_nominal = {1.0},
    .eval = eval, .partials = partials,
};
