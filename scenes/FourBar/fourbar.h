/*
 * fourbar.h - a planar four-bar linkage (a double-wishbone wheel suspension) in
 * index-1 form, shared by the scenes FourBar (SI units) and FourBarScaled (kN
 * and mm).  FourBarScaled/fourbar.h is a symbolic link to this file.
 *
 * Joint angles q = (th1, th2, th3): lower arm A-B (length L1, from horizontal),
 * upright B-C (L2, from vertical) and upper arm D-C (L3, from horizontal), with
 * e(a) = (cos a, sin a) and n(a) = (-sin a, cos a):
 *
 *   loop closure  Phi(q) = L1 e(th1) + L2 n(th2) - L3 e(th3) - D = 0   (2 equations)
 *
 * holds at the start (the pivot D is placed where the links meet for th = 0.1)
 * and is kept at acceleration level (index 1; D drops out), with the loop
 * force lambda at C as algebraic variables:
 *
 *   der(th_i) = om_i,   der(om_i) = al_i
 *   0 = M al + G(q)^T lambda - Q(q, om)      (3 moment balances, N m)
 *   0 = G(q) al + h(q, om)                   (2 loop accelerations, m/s^2)
 *
 * G = dPhi/dq = [L1 n(th1), -L2 e(th2), -L3 n(th3)], h = d(G) om = -L1 e(th1) om1^2
 * - L2 n(th2) om2^2 + L3 e(th3) om3^2.  M = diag(m1 L1^2/3 + mB L1^2, 0, m3 L3^2/3
 * + mC L3^2): arms with point masses at B and C, a massless upright.  Q: gravity,
 * a torsion spring-damper on the lower arm at A, and the tyre force (FY, FZ) at
 * P = B + PN n(th2) + PT e(th2) on the upright.
 *
 * The model's interface uses FOURBAR_LENGTH_UNIT metres and FOURBAR_FORCE_UNIT
 * newtons: lambda is in force units, the moment rows in force x length units and
 * the loop rows in length units per s^2; angles are in rad either way.  The
 * equations are evaluated in SI and converted at the interface.
 */
#ifndef FOURBAR_H
#define FOURBAR_H

#include <math.h>

#include "dae_model.h"

#define NX 6
#define NW 5
#define NU 0
#define NY 0

#define L1 0.35      /* m, lower arm */
#define L2 0.30      /* m, upright */
#define L3 0.30      /* m, upper arm */
#define TH_START 0.1 /* rad, all three angles at the start (the loop closes there) */
#define M1 4.0       /* kg, lower arm (uniform bar) */
#define MB 20.0      /* kg, point mass at B */
#define M3 2.0       /* kg, upper arm */
#define MC 10.0      /* kg, point mass at C */
#define GRAV 9.81    /* m/s^2 */
#define FZ 1.0e4     /* N, vertical tyre force */
#define FY (-1.0e4)  /* N, lateral tyre force */
#define PN (-0.1)    /* m, contact point below B along the upright */
#define PT 0.3       /* m, contact point outboard of the upright */
#define KSPRING 4.0e4 /* N m/rad */
#define CDAMP 100.0  /* N m s/rad */
#define TH_REF (-0.013) /* rad, spring rest angle (static equilibrium near th1 = 0.08) */

static const double RSCALE[NW] = {
    FOURBAR_FORCE_UNIT * FOURBAR_LENGTH_UNIT, FOURBAR_FORCE_UNIT * FOURBAR_LENGTH_UNIT,
    FOURBAR_FORCE_UNIT * FOURBAR_LENGTH_UNIT, FOURBAR_LENGTH_UNIT, FOURBAR_LENGTH_UNIT};

#define MASS1 (M1 * L1 * L1 / 3.0 + MB * L1 * L1)
#define MASS3 (M3 * L3 * L3 / 3.0 + MC * L3 * L3)

/* Residuals in SI and their partial derivatives (SI, lambda in N). */
static void fourbar_si(const double x[], const double w[], double res[],
                       double dq[NW][3], double dom[NW][3], double dal[NW][3],
                       double dlam[NW][2]) {
    const double c1 = cos(x[0]), s1 = sin(x[0]), c2 = cos(x[1]), s2 = sin(x[1]);
    const double c3 = cos(x[2]), s3 = sin(x[2]);
    const double om1 = x[3], om2 = x[4], om3 = x[5];
    const double al1 = w[0], al2 = w[1], al3 = w[2];
    const double lx = w[3] * FOURBAR_FORCE_UNIT, ly = w[4] * FOURBAR_FORCE_UNIT;
    const double wB = (M1 / 2.0 + MB) * GRAV * L1, wC = (M3 / 2.0 + MC) * GRAV * L3;
    int i, j;

    /* moment balances: M al + G^T lambda - Q */
    res[0] = MASS1 * al1 + L1 * (-s1 * lx + c1 * ly)
             - (-wB * c1 + L1 * (-FY * s1 + FZ * c1) - KSPRING * (x[0] - TH_REF) - CDAMP * om1);
    res[1] = -L2 * (c2 * lx + s2 * ly)
             - (-PN * (FY * c2 + FZ * s2) + PT * (-FY * s2 + FZ * c2));
    res[2] = MASS3 * al3 - L3 * (-s3 * lx + c3 * ly) - (-wC * c3);
    /* loop closure at acceleration level: G al + h */
    res[3] = -L1 * s1 * al1 - L2 * c2 * al2 + L3 * s3 * al3
             - L1 * c1 * om1 * om1 + L2 * s2 * om2 * om2 + L3 * c3 * om3 * om3;
    res[4] = L1 * c1 * al1 - L2 * s2 * al2 - L3 * c3 * al3
             - L1 * s1 * om1 * om1 - L2 * c2 * om2 * om2 + L3 * s3 * om3 * om3;

    if (!dq) return;
    for (i = 0; i < NW; i++)
        for (j = 0; j < 3; j++) dq[i][j] = dom[i][j] = dal[i][j] = 0.0;
    dq[0][0] = L1 * (-c1 * lx - s1 * ly) - (wB * s1 + L1 * (-FY * c1 - FZ * s1) - KSPRING);
    dom[0][0] = CDAMP;
    dal[0][0] = MASS1;
    dlam[0][0] = -L1 * s1;  dlam[0][1] = L1 * c1;

    dq[1][1] = -L2 * (-s2 * lx + c2 * ly) - (-PN * (-FY * s2 + FZ * c2) + PT * (-FY * c2 - FZ * s2));
    dlam[1][0] = -L2 * c2;  dlam[1][1] = -L2 * s2;

    dq[2][2] = -L3 * (-c3 * lx - s3 * ly) - wC * s3;
    dal[2][2] = MASS3;
    dlam[2][0] = L3 * s3;   dlam[2][1] = -L3 * c3;

    dq[3][0] = -L1 * c1 * al1 + L1 * s1 * om1 * om1;
    dq[3][1] = L2 * s2 * al2 + L2 * c2 * om2 * om2;
    dq[3][2] = L3 * c3 * al3 - L3 * s3 * om3 * om3;
    dom[3][0] = -2.0 * L1 * c1 * om1;
    dom[3][1] = 2.0 * L2 * s2 * om2;
    dom[3][2] = 2.0 * L3 * c3 * om3;
    dal[3][0] = -L1 * s1;  dal[3][1] = -L2 * c2;  dal[3][2] = L3 * s3;
    dlam[3][0] = dlam[3][1] = 0.0;

    dq[4][0] = -L1 * s1 * al1 - L1 * c1 * om1 * om1;
    dq[4][1] = -L2 * c2 * al2 + L2 * s2 * om2 * om2;
    dq[4][2] = L3 * s3 * al3 + L3 * c3 * om3 * om3;
    dom[4][0] = -2.0 * L1 * s1 * om1;
    dom[4][1] = -2.0 * L2 * c2 * om2;
    dom[4][2] = 2.0 * L3 * s3 * om3;
    dal[4][0] = L1 * c1;  dal[4][1] = -L2 * s2;  dal[4][2] = -L3 * c3;
    dlam[4][0] = dlam[4][1] = 0.0;
}

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    int i;
    (void)t; (void)u; (void)y;
    for (i = 0; i < 3; i++) {
        der[i] = x[3 + i];
        der[3 + i] = w[i];
    }
    fourbar_si(x, w, res, NULL, NULL, NULL, NULL);
    for (i = 0; i < NW; i++) res[i] /= RSCALE[i];
}

static void partials(double t, const double x[], const double w[], const double u[],
                     double J[]) {
    double res[NW], dq[NW][3], dom[NW][3], dal[NW][3], dlam[NW][2];
    int i, j;
    (void)t; (void)u;
    for (i = 0; i < 3; i++) {
        D_DER_X(i, 3 + i) = 1.0;
        D_DER_W(3 + i, i) = 1.0;
    }
    fourbar_si(x, w, res, dq, dom, dal, dlam);
    for (i = 0; i < NW; i++) {
        for (j = 0; j < 3; j++) {
            D_RES_X(i, j) = dq[i][j] / RSCALE[i];
            D_RES_X(i, 3 + j) = dom[i][j] / RSCALE[i];
            D_RES_W(i, j) = dal[i][j] / RSCALE[i];
        }
        for (j = 0; j < 2; j++) D_RES_W(i, 3 + j) = dlam[i][j] * FOURBAR_FORCE_UNIT / RSCALE[i];
    }
}

/* MODEL with the nominal of lambda in the interface's force unit. */
#define FOURBAR_MODEL(lambda_nominal)                                                   \
    const ModelDef MODEL = {                                                            \
        .nx = NX, .nw = NW, .nu = NU, .ny = NY,                                          \
        .vr_time = 0, .vr_enable = 1, .enable_tunable = fmi3False,                      \
        .vr_x   = {2, 4, 6, 8, 10, 12}, .vr_der = {3, 5, 7, 9, 11, 13},                  \
        .vr_w   = {14, 15, 16, 17, 18}, .vr_res = {19, 20, 21, 22, 23},                  \
        .x_start = {TH_START, TH_START, TH_START, 0.0, 0.0, 0.0},                        \
        .w_start = {0.0, 0.0, 0.0, 0.0, 0.0},                                            \
        .x_nominal = {0.1, 0.1, 0.1, 1.0, 1.0, 1.0},                                     \
        .w_nominal = {100.0, 100.0, 100.0, (lambda_nominal), (lambda_nominal)},          \
        .eval = eval, .partials = partials,                                             \
    }

#endif /* FOURBAR_H */
