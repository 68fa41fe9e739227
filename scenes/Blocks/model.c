/*
 * Blocks - a scalable DAE with wide coupling: N algebraic variables in blocks of B = 10, each
 * residual coupled to every variable of its own block and of the two blocks beside it.
 *
 *   der(x) = w[0] - x
 *        0 = 4*w[i] + sin(w[i]) - 0.1 * (sum of the other w of i's block)
 *                               - 0.05 * (sum of the w of the blocks before and after i's)
 *                               - 0.5 * x   (the first block)   - 0.5 * u   (the last block)
 *                                                               (r[i], i = 0..N-1)
 *        y = w[N-1]
 *
 * dg/dw is block tridiagonal with dense 10 x 10 blocks: 30 structural nonzeros in every
 * residual's row (10 times the Chain's), a lower and upper bandwidth of 19, and it is
 * strictly diagonally dominant (diagonal 4 + cos(w) in [3, 5], the other entries of a row add
 * up to at most 0.9 + 1.0), so it stays well conditioned for every N. A Curtis-Powell-Reid
 * colouring of the Jacobian needs about 5 B = 50 groups (columns up to two blocks apart share
 * a row), whatever N is.
 *
 * The model uses the framework's sparse interface (dae_model.h): `pattern` lists the
 * structural nonzeros with the dependenciesKind of the manifest, `partials_sparse` their
 * values, so the framework's derivative calls are O(nnz) and its Newton step a band LU of
 * bandwidth 19, O(N).
 *
 * N = BLOCKS_N (default 30), a multiple of B. The XML in this folder is for N = 30;
 * scenes/Blocks/blocks.py writes it for any N and builds with -DBLOCKS_N=N
 * -DFMU_MAX_VARS=<power of two >= N>.
 * Value references: time 0, enable 1, x 2, der(x) 3, u 4, y 5, w[i] 10+2i, r[i] 11+2i.
 */
#include <math.h>
#include "dae_model.h"

#ifndef BLOCKS_N
#define BLOCKS_N 30
#endif
#define B 10

#define NX 1
#define NW BLOCKS_N
#define NU 1
#define NY 1
#define NB (NW / B)

#if BLOCKS_N > FMU_MAX_VARS || BLOCKS_N < 2 * B || BLOCKS_N % B != 0
#error "Blocks needs BLOCKS_N a multiple of 10, from 20 to FMU_MAX_VARS"
#endif

#define IN_BLOCK 0.1     /* coupling to the other variables of the block */
#define BESIDE 0.05      /* coupling to the variables of the neighbouring blocks */
#define BOUNDARY 0.5     /* x into the first block, u into the last */

static void eval(double t, const double x[], const double w[], const double u[],
                 double der[], double res[], double y[]) {
    int b, i, j;
    (void)t;
    for (b = 0; b < NB; b++) {
        double own = 0.0, beside = 0.0;
        for (j = b * B; j < (b + 1) * B; j++) own += w[j];
        if (b > 0) for (j = (b - 1) * B; j < b * B; j++) beside += w[j];
        if (b < NB - 1) for (j = (b + 1) * B; j < (b + 2) * B; j++) beside += w[j];
        for (i = b * B; i < (b + 1) * B; i++) {
            res[i] = 4 * w[i] + sin(w[i]) - IN_BLOCK * (own - w[i]) - BESIDE * beside;
            if (b == 0) res[i] -= BOUNDARY * x[0];
            if (b == NB - 1) res[i] -= BOUNDARY * u[0];
        }
    }
    der[0] = w[0] - x[0];
    y[0] = w[NW - 1];
}

/*
 * The Jacobian's structural nonzeros, in one fixed order: their positions and kinds into
 * e[] (when e is not NULL) and their values at w into v[] (when v is not NULL); returns
 * their number.
 */
#define ENTRY(r, c, kd, value)                                                     \
    do {                                                                           \
        if (e) { e[k].row = (r); e[k].col = (c); e[k].kind = (kd); }               \
        if (v) v[k] = (value);                                                     \
        k++;                                                                       \
    } while (0)

static int jacobian(const double w[], ModelEntry e[], double v[]) {
    int b, i, j, k = 0;
    ENTRY(ROW_DER(0), COL_X(0), fmi3Constant, -1.0);
    ENTRY(ROW_DER(0), COL_W(0), fmi3Constant, 1.0);
    ENTRY(ROW_OUT(0), COL_W(NW - 1), fmi3Constant, 1.0);
    for (b = 0; b < NB; b++) {
        const int first = (b > 0 ? b - 1 : 0) * B, last = (b < NB - 1 ? b + 2 : NB) * B;
        for (i = b * B; i < (b + 1) * B; i++) {
            if (b == 0) ENTRY(ROW_RES(i), COL_X(0), fmi3Constant, -BOUNDARY);
            for (j = first; j < last; j++) {
                if (j == i) ENTRY(ROW_RES(i), COL_W(j), fmi3Dependent, 4 + cos(w[i]));
                else if (j / B == b) ENTRY(ROW_RES(i), COL_W(j), fmi3Constant, -IN_BLOCK);
                else ENTRY(ROW_RES(i), COL_W(j), fmi3Constant, -BESIDE);
            }
            if (b == NB - 1) ENTRY(ROW_RES(i), COL_U(0), fmi3Constant, -BOUNDARY);
        }
    }
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

#if FMU_MAX_VARS == 32
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
#error "Blocks needs FMU_MAX_VARS to be a power of two from 32 to 16384"
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
