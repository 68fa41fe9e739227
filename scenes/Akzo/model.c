/*
 * Akzo - the Chemical Akzo Nobel problem ("chemakzo" of the test set for IVP
 * solvers): 5 concentrations as states, y6 as the algebraic variable.
 *
 *   r1 = k1*y1^4*sqrt(y2)       r2 = k2*y3*y4        r3 = k2/K*y1*y5
 *   r4 = k3*y1*y4^2             r5 = k4*y6^2*sqrt(y2)
 *   Fin = klA*(pCO2/H - y2)
 *
 *   der(y1) = -2*r1 + r2 - r3 - r4
 *   der(y2) = -0.5*r1 - r4 - 0.5*r5 + Fin
 *   der(y3) = r1 - r2 + r3
 *   der(y4) = -r2 + r3 - 2*r4
 *   der(y5) = r2 - r3 + r5
 *         0 = Ks*y1*y4 - y6                                (residual)
 *
 * sqrt(y2) has no real value for y2 < 0 (and no derivative at 0): the model
 * then calls model_discard(), so the FMU returns fmi3Discard instead of NaN.
 *
 * AKZO_NO_CO2_FEED (a -D define) sets klA = 0: without the CO2 feed, y2 is used
 * up near t = 0.18 (sqrt(y2) falls linearly) and r4 then drives it below zero,
 * into the region where sqrt(y2) is undefined: no step size gets past it.
 */
#include <math.h>

#include "dae_model.h"

#define NX 5
#define NW 1
#define NU 0
#define NY 0

#define K1   18.7
#define K2   0.58
#define K3   0.09
#define K4   0.42
#define KBIG 34.4
#define PCO2 0.9
#define HENRY 737.0
#define KS   115.83
#ifdef AKZO_NO_CO2_FEED
#define KLA  0.0
#else
#define KLA  3.3
#endif

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    const double y1 = x[0], y2 = x[1], y3 = x[2], y4 = x[3], y5 = x[4], y6 = w[0];
    double s2, r1, r2, r3, r4, r5, fin;
    (void)t; (void)u; (void)y;
    if (!(y2 >= 0.0)) model_discard("sqrt(y2) with y2 < 0: the CO2 concentration is negative");
    s2 = sqrt(y2);   /* NaN when discarded; the framework does not use the values then */
    r1 = K1 * y1 * y1 * y1 * y1 * s2;
    r2 = K2 * y3 * y4;
    r3 = K2 / KBIG * y1 * y5;
    r4 = K3 * y1 * y4 * y4;
    r5 = K4 * y6 * y6 * s2;
    fin = KLA * (PCO2 / HENRY - y2);
    der[0] = -2.0 * r1 + r2 - r3 - r4;
    der[1] = -0.5 * r1 - r4 - 0.5 * r5 + fin;
    der[2] = r1 - r2 + r3;
    der[3] = -r2 + r3 - 2.0 * r4;
    der[4] = r2 - r3 + r5;
    res[0] = KS * y1 * y4 - y6;
}

static void partials(double t, const double x[], const double w[], const double u[],
                     double J[]) {
    const double y1 = x[0], y2 = x[1], y3 = x[2], y4 = x[3], y5 = x[4], y6 = w[0];
    double s2, dr1[5], dr2[5], dr3[5], dr4[5], dr5[6];
    int j;
    (void)t; (void)u;
    if (!(y2 > 0.0)) model_discard("d sqrt(y2)/d y2 with y2 <= 0");
    s2 = sqrt(y2);
    /* gradients of the rates with respect to y1..y5 (and y6 for r5) */
    for (j = 0; j < 5; j++) dr1[j] = dr2[j] = dr3[j] = dr4[j] = dr5[j] = 0.0;
    dr1[0] = 4.0 * K1 * y1 * y1 * y1 * s2;
    dr1[1] = K1 * y1 * y1 * y1 * y1 * 0.5 / s2;
    dr2[2] = K2 * y4;
    dr2[3] = K2 * y3;
    dr3[0] = K2 / KBIG * y5;
    dr3[4] = K2 / KBIG * y1;
    dr4[0] = K3 * y4 * y4;
    dr4[3] = 2.0 * K3 * y1 * y4;
    dr5[1] = K4 * y6 * y6 * 0.5 / s2;
    dr5[5] = 2.0 * K4 * y6 * s2;
    for (j = 0; j < 5; j++) {
        D_DER_X(0, j) = -2.0 * dr1[j] + dr2[j] - dr3[j] - dr4[j];
        D_DER_X(1, j) = -0.5 * dr1[j] - dr4[j] - 0.5 * dr5[j];
        D_DER_X(2, j) = dr1[j] - dr2[j] + dr3[j];
        D_DER_X(3, j) = -dr2[j] + dr3[j] - 2.0 * dr4[j];
        D_DER_X(4, j) = dr2[j] - dr3[j] + dr5[j];
    }
    D_DER_X(1, 1) -= KLA;
    D_DER_W(1, 0) = -0.5 * dr5[5];
    D_DER_W(4, 0) = dr5[5];

    D_RES_X(0, 0) = KS * y4;
    D_RES_X(0, 3) = KS * y1;
    D_RES_W(0, 0) = -1.0;
}

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 1, .enable_tunable = fmi3False,
    .vr_x   = {2, 4, 6, 8, 10}, .vr_der = {3, 5, 7, 9, 11},
    .vr_w   = {12},             .vr_res = {13},
    .x_start   = {0.444, 0.00123, 0.0, 0.007, 0.0}, .w_start = {0.36},
    .x_nominal = {0.1, 1e-3, 0.1, 1e-3, 0.01},     .w_nominal = {0.01},
    .eval = eval, .partials = partials,
};
