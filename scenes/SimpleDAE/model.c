/*
 * SimpleDAE - the example model of the fmi-ls-dae paper.
 *
 *   der(x1) = sin(x1) + sin(z1*z2*u1)
 *   der(x2) = sin(x1*x2) + sin(z1*z2*u2) + u1^2
 *         0 = z1*u1^2 + tanh(3*z1) + u2*x1^3        (__residual0)
 *         0 = exp(z1*z2*u1)/3 - sin(z2*x2)          (__residual1)
 *        y1 = u1*x1*z1 + sin(u2)
 *        y2 = u2*x2*z2 + sin(u1*u2)
 */
#include <math.h>
#include "dae_model.h"

#define NX 2
#define NW 2
#define NU 2
#define NY 2

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    const double x1 = x[0], x2 = x[1], z1 = w[0], z2 = w[1], u1 = u[0], u2 = u[1];
    (void)t;
    der[0] = sin(x1) + sin(z1 * z2 * u1);
    der[1] = sin(x1 * x2) + sin(z1 * z2 * u2) + u1 * u1;
    res[0] = z1 * u1 * u1 + tanh(3 * z1) + u2 * x1 * x1 * x1;
    res[1] = exp(z1 * z2 * u1) / 3 - sin(z2 * x2);
    y[0] = u1 * x1 * z1 + sin(u2);
    y[1] = u2 * x2 * z2 + sin(u1 * u2);
}

static void partials(double t, const double x[], const double w[], const double u[],
                     double J[]) {
    const double x1 = x[0], x2 = x[1], z1 = w[0], z2 = w[1], u1 = u[0], u2 = u[1];
    const double c1 = cos(z1 * z2 * u1), c2 = cos(z1 * z2 * u2), c12 = cos(x1 * x2);
    const double e = exp(z1 * z2 * u1) / 3, th = tanh(3 * z1), cz = cos(z2 * x2);
    (void)t;
#ifdef DEFECT_WRONG_JACOBIAN
    D_DER_X(0, 0) = -cos(x1);       /* sign error: d der(x1)/d x1 is cos(x1) */
#else
    D_DER_X(0, 0) = cos(x1);
#endif
    D_DER_W(0, 0) = c1 * z2 * u1;
    D_DER_W(0, 1) = c1 * z1 * u1;
    D_DER_U(0, 0) = c1 * z1 * z2;

    D_DER_X(1, 0) = c12 * x2;
    D_DER_X(1, 1) = c12 * x1;
    D_DER_W(1, 0) = c2 * z2 * u2;
    D_DER_W(1, 1) = c2 * z1 * u2;
    D_DER_U(1, 0) = 2 * u1;
    D_DER_U(1, 1) = c2 * z1 * z2;

    D_RES_X(0, 0) = 3 * u2 * x1 * x1;
    D_RES_W(0, 0) = u1 * u1 + 3 * (1 - th * th);
    D_RES_U(0, 0) = 2 * z1 * u1;
    D_RES_U(0, 1) = x1 * x1 * x1;

    D_RES_X(1, 1) = -z2 * cz;
    D_RES_W(1, 0) = e * z2 * u1;
    D_RES_W(1, 1) = e * z1 * u1 - x2 * cz;
    D_RES_U(1, 0) = e * z1 * z2;

    D_OUT_X(0, 0) = u1 * z1;
    D_OUT_W(0, 0) = u1 * x1;
    D_OUT_U(0, 0) = x1 * z1;
    D_OUT_U(0, 1) = cos(u2);

    D_OUT_X(1, 1) = u2 * z2;
    D_OUT_W(1, 1) = u2 * x2;
    D_OUT_U(1, 0) = u2 * cos(u1 * u2);
    D_OUT_U(1, 1) = x2 * z2 + u1 * cos(u1 * u2);
}

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 13, .enable_tunable = fmi3True,
    .vr_x   = {1, 3},   .vr_der = {2, 4},
    .vr_w   = {5, 6},   .vr_res = {11, 12},
    .vr_u   = {7, 8},   .vr_y   = {9, 10},
    .x_start = {0.5, 0.5}, .w_start = {0.0, 0.0}, .u_start = {0.0, 0.0},
    .x_nominal = {1.0, 1.0}, .w_nominal = {1.0, 1.0},
    .eval = eval, .partials = partials,
};
