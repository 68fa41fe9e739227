/*
 * Chain - a scalable DAE: N algebraic variables coupled like a discretised rod.
 *
 *   der(x) = w[0] - x
 *        0 = 4*w[i] + sin(w[i]) - w[i-1] - w[i+1]     (r[i], i = 0..N-1; w[-1] = x, w[N] = u)
 *        y = w[N-1]
 *
 * dg/dw is tridiagonal and strictly diagonally dominant (diagonal 4 + cos(w) in [3, 5],
 * off-diagonals -1), so it stays well conditioned for every N, and a Curtis-Powell-Reid
 * colouring of the whole Jacobian needs a handful of groups whatever N is.
 *
 * N = CHAIN_N (default 4). The XML in this folder is for N = 4; tests/scenes/Chain/chain.py
 * writes it for any N and builds with -DCHAIN_N=N -DFMU_MAX_VARS=<power of two >= N>.
 * Value references: time 0, enable 1, x 2, der(x) 3, u 4, y 5, w[i] 10+2i, r[i] 11+2i.
 *
 * Defects (their manifest edits are in tests/probes/defects_derivatives.py):
 *   DEFECT_SINGULAR_GW      the last residual is twice the one before it: dg/dw is singular
 *   DEFECT_ILL_CONDITIONED  the last residual is the one before it plus 1e-10 * w[N-1]
 * Both drop x and u from the residuals, so that w = 0 solves them at every point and the
 * framework's own Newton iteration (ODE mode, initialisation) never has to factor dg/dw.
 */
#include <math.h>
#include "dae_model.h"

#ifndef CHAIN_N
#define CHAIN_N 4
#endif

#define NX 1
#define NW CHAIN_N
#define NU 1
#define NY 1

#if CHAIN_N > FMU_MAX_VARS || CHAIN_N < 3
#error "Chain needs 3 <= CHAIN_N <= FMU_MAX_VARS"
#endif

#if defined(DEFECT_SINGULAR_GW) || defined(DEFECT_ILL_CONDITIONED)
#define COUPLED 0.0     /* x and u do not enter the residuals */
#else
#define COUPLED 1.0
#endif

#ifdef DEFECT_SINGULAR_GW
#define LAST_SCALE 2.0
#define LAST_EXTRA 0.0
#elif defined(DEFECT_ILL_CONDITIONED)
#define LAST_SCALE 1.0
#define LAST_EXTRA 1e-10
#endif

/* r[i] for the regular chain, w[-1] = x, w[N] = u */
static double link(const double w[], int i, double x, double u) {
    const double left = i > 0 ? w[i - 1] : COUPLED * x;
    const double right = i < NW - 1 ? w[i + 1] : COUPLED * u;
    return 4 * w[i] + sin(w[i]) - left - right;
}

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    int i;
    (void)t;
    for (i = 0; i < NW; i++) res[i] = link(w, i, x[0], u[0]);
#ifdef LAST_SCALE
    res[NW - 1] = LAST_SCALE * link(w, NW - 2, x[0], u[0]) + LAST_EXTRA * w[NW - 1];
#endif
    der[0] = w[0] - x[0];
    y[0] = w[NW - 1];
}

static void partials(double t, const double x[], const double w[], const double u[],
                     double J[]) {
    int i;
    (void)t; (void)x; (void)u;
    D_DER_X(0, 0) = -1;
    D_DER_W(0, 0) = 1;
    D_OUT_W(0, NW - 1) = 1;
    for (i = 0; i < NW; i++) {
        D_RES_W(i, i) = 4 + cos(w[i]);
        if (i > 0) D_RES_W(i, i - 1) = -1;
        if (i < NW - 1) D_RES_W(i, i + 1) = -1;
    }
    D_RES_X(0, 0) = -COUPLED;
    D_RES_U(NW - 1, 0) = -COUPLED;
#ifdef LAST_SCALE
    D_RES_W(NW - 1, NW - 3) = -LAST_SCALE;
    D_RES_W(NW - 1, NW - 2) = LAST_SCALE * (4 + cos(w[NW - 2]));
    D_RES_W(NW - 1, NW - 1) = -LAST_SCALE + LAST_EXTRA;
#endif
}

/* FMU_MAX_VARS entries of base + step*i (a vr table) or of a constant, by doubling. */
#define SEQ1(b, s, i) (b) + (s) * (i)
#define SEQ2(b, s, i) SEQ1(b, s, i), SEQ1(b, s, (i) + 1)
#define SEQ4(b, s, i) SEQ2(b, s, i), SEQ2(b, s, (i) + 2)
#define SEQ8(b, s, i) SEQ4(b, s, i), SEQ4(b, s, (i) + 4)
#define SEQ16(b, s, i) SEQ8(b, s, i), SEQ8(b, s, (i) + 8)
#define SEQ32(b, s, i) SEQ16(b, s, i), SEQ16(b, s, (i) + 16)
#define SEQ64(b, s, i) SEQ32(b, s, i), SEQ32(b, s, (i) + 32)
#define SEQ128(b, s, i) SEQ64(b, s, i), SEQ64(b, s, (i) + 64)
#define SEQ256(b, s, i) SEQ128(b, s, i), SEQ128(b, s, (i) + 128)
#define SEQ512(b, s, i) SEQ256(b, s, i), SEQ256(b, s, (i) + 256)
#define SEQ1024(b, s, i) SEQ512(b, s, i), SEQ512(b, s, (i) + 512)
#define SEQ2048(b, s, i) SEQ1024(b, s, i), SEQ1024(b, s, (i) + 1024)
#define SEQ4096(b, s, i) SEQ2048(b, s, i), SEQ2048(b, s, (i) + 2048)

#if FMU_MAX_VARS == 8
#define TABLE(b, s) { SEQ8(b, s, 0) }
#elif FMU_MAX_VARS == 16
#define TABLE(b, s) { SEQ16(b, s, 0) }
#elif FMU_MAX_VARS == 32
#define TABLE(b, s) { SEQ32(b, s, 0) }
#elif FMU_MAX_VARS == 64
#define TABLE(b, s) { SEQ64(b, s, 0) }
#elif FMU_MAX_VARS == 128
#define TABLE(b, s) { SEQ128(b, s, 0) }
#elif FMU_MAX_VARS == 256
#define TABLE(b, s) { SEQ256(b, s, 0) }
#elif FMU_MAX_VARS == 512
#define TABLE(b, s) { SEQ512(b, s, 0) }
#elif FMU_MAX_VARS == 1024
#define TABLE(b, s) { SEQ1024(b, s, 0) }
#elif FMU_MAX_VARS == 2048
#define TABLE(b, s) { SEQ2048(b, s, 0) }
#elif FMU_MAX_VARS == 4096
#define TABLE(b, s) { SEQ4096(b, s, 0) }
#else
#error "Chain needs FMU_MAX_VARS to be a power of two from 8 to 4096"
#endif

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 1, .enable_tunable = fmi3False,
    .vr_x = {2}, .vr_der = {3},
    .vr_w = TABLE(10, 2), .vr_res = TABLE(11, 2),
    .vr_u = {4}, .vr_y = {5},
    .x_start = {1.0}, .w_start = {0.0}, .u_start = {0.0},
    .x_nominal = {1.0}, .w_nominal = TABLE(1.0, 0.0),
    .eval = eval, .partials = partials,
};
