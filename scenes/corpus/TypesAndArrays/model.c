/*
 * TypesAndArrays - Model Exchange, one variable of every FMI 3.0 type.
 *
 *   der(x) = -rate x, rate = 1 (off: 0, fast: 2 per mode)
 *   y[i]   = gains[i] * x * scale * (matrix[0][0] + matrix[1][1]) / 2
 *   total  = i8 + u8 + i16 + u16 + i32 + u32 + i64 + u64 + offsets[0] + offsets[1]
 *   disabled = !enabled, labelLength = strlen(label), blobSize = size of blob,
 *   status = "mode <n>", ticks += 1 at every tick of the input Clock tick.
 */
#include <stdio.h>
#include <string.h>

#include "corpus_model.h"

enum { VR_TIME, VR_X, VR_DER_X, VR_GAINS, VR_MATRIX, VR_Y, VR_SCALE, VR_I8, VR_U8, VR_I16,
       VR_U16, VR_I32, VR_U32, VR_I64, VR_U64, VR_TOTAL, VR_ENABLED, VR_DISABLED, VR_LABEL,
       VR_LABEL_LENGTH, VR_BLOB, VR_BLOB_SIZE, VR_MODE, VR_STATUS, VR_OFFSETS, VR_TICK,
       VR_TICKS };

static const VarDef VARS[] = {
    {VR_TIME, "time", T_FLOAT64, CA_INDEPENDENT, VA_CONTINUOUS, IN_NONE, 1, NO_VR, NULL},
    {VR_X, "x", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "1"},
    {VR_DER_X, "der(x)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_GAINS, "gains", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 3, NO_VR, "1 2 3"},
    {VR_MATRIX, "matrix", T_FLOAT64, CA_PARAMETER, VA_TUNABLE, IN_EXACT, 4, NO_VR, "1 0 0 1"},
    {VR_Y, "y", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_CALCULATED, 3, NO_VR, NULL},
    {VR_SCALE, "scale", T_FLOAT32, CA_INPUT, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "1.5"},
    {VR_I8, "i8", T_INT8, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "-8"},
    {VR_U8, "u8", T_UINT8, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "8"},
    {VR_I16, "i16", T_INT16, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "-16"},
    {VR_U16, "u16", T_UINT16, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "16"},
    {VR_I32, "i32", T_INT32, CA_PARAMETER, VA_TUNABLE, IN_EXACT, 1, NO_VR, "-32"},
    {VR_U32, "u32", T_UINT32, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "32"},
    {VR_I64, "i64", T_INT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "-64"},
    {VR_U64, "u64", T_UINT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "64"},
    {VR_TOTAL, "total", T_INT64, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_ENABLED, "enabled", T_BOOLEAN, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "true"},
    {VR_DISABLED, "disabled", T_BOOLEAN, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_LABEL, "label", T_STRING, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "hello, corpus"},
    {VR_LABEL_LENGTH, "labelLength", T_UINT32, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR,
     NULL},
    {VR_BLOB, "blob", T_BINARY, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "00ff10"},
    {VR_BLOB_SIZE, "blobSize", T_UINT64, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_MODE, "mode", T_ENUMERATION, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "2"},
    {VR_STATUS, "status", T_STRING, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_OFFSETS, "offsets", T_INT16, CA_LOCAL, VA_CONSTANT, IN_EXACT, 2, NO_VR, "10 20"},
    {VR_TICK, "tick", T_CLOCK, CA_INPUT, VA_DISCRETE, IN_NONE, 1, NO_VR, NULL},
    {VR_TICKS, "ticks", T_INT32, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
};

static const fmi3ValueReference STATES[] = {VR_X};
static const fmi3ValueReference DERIVATIVES[] = {VR_DER_X};

static void calculate(Instance *c) {
    const double *gains = f64(c, VR_GAINS), *m = f64(c, VR_MATRIX);
    const fmi3Int64 *offsets = i64(c, VR_OFFSETS);
    double x = *f64(c, VR_X), factor = *f64(c, VR_SCALE) * (m[0] + m[3]) / 2.0;
    fmi3Int64 mode = *i64(c, VR_MODE);
    double rate = mode == 1 ? 0.0 : mode == 3 ? 2.0 : 1.0;
    size_t k, n;
    char status[32];
    *f64(c, VR_TIME) = fmu_time(c);
    *f64(c, VR_DER_X) = -rate * x;
    for (k = 0; k < count(c, VR_Y); k++) f64(c, VR_Y)[k] = gains[k] * x * factor;
    *i64(c, VR_TOTAL) = *i64(c, VR_I8) + (fmi3Int64)*u64(c, VR_U8) + *i64(c, VR_I16)
        + (fmi3Int64)*u64(c, VR_U16) + *i64(c, VR_I32) + (fmi3Int64)*u64(c, VR_U32)
        + *i64(c, VR_I64) + (fmi3Int64)*u64(c, VR_U64) + offsets[0] + offsets[1];
    *flag(c, VR_DISABLED) = !*flag(c, VR_ENABLED);
    *u64(c, VR_LABEL_LENGTH) = strlen(string_value(c, VR_LABEL));
    binary_value(c, VR_BLOB, &n);
    *u64(c, VR_BLOB_SIZE) = n;
    snprintf(status, sizeof status, "mode %d", (int)mode);
    set_string(c, VR_STATUS, status);
}

static void tick(Instance *c, fmi3ValueReference clock) {
    if (clock == VR_TICK) *i64(c, VR_TICKS) += 1;
}

const ModelDef MODEL = {
    VARS, sizeof VARS / sizeof VARS[0], IF_ME,
    1, STATES, DERIVATIVES, 0, 0.001,
    calculate, NULL, NULL, tick,
};
