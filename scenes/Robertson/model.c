/*
 * Robertson - stiff chemical kinetics with the mass balance as the
 * algebraic equation (y3 is the algebraic variable).
 *
 *   der(y1) = -0.04*y1 + 1e4*y2*y3
 *   der(y2) =  0.04*y1 - 1e4*y2*y3 - 3e7*y2^2
 *         0 = y1 + y2 + y3 - 1                     (residual)
 */
#include "dae_model.h"

#ifdef DEFECT_HIDDEN_STATE
/* Defect: the residual depends on the history of calls. Every jump to a distant point (more
 * than 0.01 in nominal-scaled distance) shifts it by 1e-9, like a warm-started inner solve
 * that stops early. Small (finite-difference) steps do not move it, so it shows only when the
 * same point is evaluated again after another one. */
static double hidden_offset(double t, const double x[]) {
    static double last[3];
    static int have_last = 0;
    static long jumps = 0;
    const double now[3] = {t, x[0], x[1] / 1e-5};
    double d2 = 0.0;
    int i;
    for (i = 0; i < 3; i++) {
        d2 += (now[i] - last[i]) * (now[i] - last[i]);
        last[i] = now[i];
    }
    if (have_last && d2 > 1e-4) jumps++;
    have_last = 1;
    return 1e-9 * (double)jumps;
}
#endif

#define NX 2
#define NW 1
#define NU 0
#define NY 0

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    const double y1 = x[0], y2 = x[1], y3 = w[0];
    (void)t; (void)u; (void)y;
    der[0] = -0.04 * y1 + 1e4 * y2 * y3;
    der[1] = 0.04 * y1 - 1e4 * y2 * y3 - 3e7 * y2 * y2;
    res[0] = y1 + y2 + y3 - 1;
#ifdef DEFECT_HIDDEN_STATE
    res[0] += hidden_offset(t, x);
#endif
}

static void partials(double t, const double x[], const double w[], const double u[],
                     double J[]) {
    const double y2 = x[1], y3 = w[0];
    (void)t; (void)u;
    D_DER_X(0, 0) = -0.04;
    D_DER_X(0, 1) = 1e4 * y3;
    D_DER_W(0, 0) = 1e4 * y2;

    D_DER_X(1, 0) = 0.04;
    D_DER_X(1, 1) = -1e4 * y3 - 6e7 * y2;
    D_DER_W(1, 0) = -1e4 * y2;

    D_RES_X(0, 0) = 1;
    D_RES_X(0, 1) = 1;
    D_RES_W(0, 0) = 1;
}

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 1, .enable_tunable = fmi3False,
    .vr_x   = {2, 4},   .vr_der = {3, 5},
    .vr_w   = {6},      .vr_res = {7},
    .x_start = {1.0, 0.0}, .w_start = {0.0},
    .x_nominal = {1.0, 1e-5}, .w_nominal = {1.0},
    .eval = eval, .partials = partials,
};
