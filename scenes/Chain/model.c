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
 * The model uses the framework's sparse interface (dae_model.h): `pattern` lists the 3N + 3
 * structural nonzeros with the dependenciesKind of the manifest, `partials_sparse` their
 * values, both from one walk over the entries (jacobian() below), so the framework's
 * derivative calls, Newton steps and per-element dependencies are O(N).
 *
 * N = CHAIN_N (default 4). The XML in this folder is for N = 4; scenes/Chain/chain.py
 * writes it for any N and builds with -DCHAIN_N=N -DFMU_MAX_VARS=<power of two >= N>
 * (the capacity of ModelDef's tables).
 * Value references: time 0, enable 1, x 2, der(x) 3, u 4, y 5, w[i] 10+2i, r[i] 11+2i.
 *
 * Defects (their manifest edits are in tests/fixtures/defects/derivatives.py):
 *   DEFECT_SINGULAR_GW       the last residual is twice the one before it: dg/dw is singular
 *   DEFECT_ILL_CONDITIONED   the last residual is the one before it plus 1e-10 * w[N-1]
 * Both drop x and u from the residuals, so that w = 0 solves them at every point and the
 * framework's own Newton iteration (ODE mode, initialisation) never has to factor dg/dw.
 *   DEFECT_EXTRA_DEPENDENCY  the pattern also lists d(y)/d(x) (always zero): in DAE mode
 *                            fmi3GetVariableDependencies reports y depending on x, which
 *                            the manifest does not list
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

/*
 * The Jacobian's structural nonzeros, in one fixed order: their positions and kinds into
 * e[] (when e is not NULL) and their values at w into v[] (when v is not NULL); returns
 * their number.  An entry's value expression is only evaluated when v is given.
 */
#define ENTRY(r, c, kd, value)                                                     \
    do {                                                                           \
        if (e) { e[k].row = (r); e[k].col = (c); e[k].kind = (kd); }               \
        if (v) v[k] = (value);                                                     \
        k++;                                                                       \
    } while (0)

static int jacobian(const double w[], ModelEntry e[], double v[]) {
    int i, k = 0;
    ENTRY(ROW_DER(0), COL_X(0), fmi3Constant, -1.0);
    ENTRY(ROW_DER(0), COL_W(0), fmi3Constant, 1.0);
    ENTRY(ROW_OUT(0), COL_W(NW - 1), fmi3Constant, 1.0);
#ifdef DEFECT_EXTRA_DEPENDENCY
    ENTRY(ROW_OUT(0), COL_X(0), fmi3Constant, 0.0);
#endif
    for (i = 0; i < NW; i++) {
#ifdef LAST_SCALE
        if (i == NW - 1) break;
#endif
        if (i > 0) ENTRY(ROW_RES(i), COL_W(i - 1), fmi3Constant, -1.0);
        if (COUPLED != 0.0 && i == 0) ENTRY(ROW_RES(0), COL_X(0), fmi3Constant, -COUPLED);
        if (COUPLED != 0.0 && i == NW - 1) ENTRY(ROW_RES(i), COL_U(0), fmi3Constant, -COUPLED);
        ENTRY(ROW_RES(i), COL_W(i), fmi3Dependent, 4 + cos(w[i]));
        if (i < NW - 1) ENTRY(ROW_RES(i), COL_W(i + 1), fmi3Constant, -1.0);
    }
#ifdef LAST_SCALE
    ENTRY(ROW_RES(NW - 1), COL_W(NW - 3), fmi3Constant, -LAST_SCALE);
    ENTRY(ROW_RES(NW - 1), COL_W(NW - 2), fmi3Dependent, LAST_SCALE * (4 + cos(w[NW - 2])));
    ENTRY(ROW_RES(NW - 1), COL_W(NW - 1), fmi3Constant, -LAST_SCALE + LAST_EXTRA);
#endif
    return k;
}

static int pattern(ModelEntry entries[]) {
    return jacobian(NULL, entries, NULL);
}

static void partials_sparse(double t, const double x[], const double w[], const double u[],
                            double values[]) {
    (void)t; (void)x; (void)u;
    jacobian(w, NULL, values);
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
#define SEQ8192(b, s, i) SEQ4096(b, s, i), SEQ4096(b, s, (i) + 4096)
#define SEQ16384(b, s, i) SEQ8192(b, s, i), SEQ8192(b, s, (i) + 8192)

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
#elif FMU_MAX_VARS == 8192
#define TABLE(b, s) { SEQ8192(b, s, 0) }
#elif FMU_MAX_VARS == 16384
#define TABLE(b, s) { SEQ16384(b, s, 0) }
#else
#error "Chain needs FMU_MAX_VARS to be a power of two from 8 to 16384"
#endif

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 1, .enable_tunable = fmi3False,
    .vr_x = {2}, .vr_der = {3},
    .vr_w = TABLE(10, 2), .vr_res = TABLE(11, 2),
    .vr_u = {4}, .vr_y = {5},
    .x_start = {1.0}, .w_start = {0.0}, .u_start = {0.0},
    .x_nominal = {1.0}, .w_nominal = TABLE(1.0, 0.0),
    .eval = eval, .partials = NULL, .pattern = pattern, .partials_sparse = partials_sparse,
};
