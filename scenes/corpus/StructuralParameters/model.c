/*
 * StructuralParameters - der(x) = -x, y[i] = gainScale gains[i] x (+ offset if useOffset),
 * i = 1..n. Model Exchange and Co-Simulation.
 *
 * n (UInt64, fixed) sizes gains and y (at most 8); useOffset is a Boolean structural
 * parameter that no Dimension references (FMI 3.0 allows it, MV-42; it is not an
 * fmi-ls-dae enable parameter); gainScale is tunable, so Reconfiguration Mode exists.
 */
#include "corpus_model.h"

enum { VR_TIME, VR_N, VR_USE_OFFSET, VR_GAIN_SCALE, VR_GAINS, VR_OFFSET, VR_X, VR_DER_X, VR_Y };

static const VarDef VARS[] = {
    {VR_TIME, "time", T_FLOAT64, CA_INDEPENDENT, VA_CONTINUOUS, IN_NONE, 1, NO_VR, NULL},
    {VR_N, "n", T_UINT64, CA_STRUCTURAL_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "3"},
    {VR_USE_OFFSET, "useOffset", T_BOOLEAN, CA_STRUCTURAL_PARAMETER, VA_FIXED, IN_EXACT, 1,
     NO_VR, "false"},
    {VR_GAIN_SCALE, "gainScale", T_FLOAT64, CA_STRUCTURAL_PARAMETER, VA_TUNABLE, IN_EXACT, 1,
     NO_VR, "1"},
    {VR_GAINS, "gains", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 8, VR_N, "0.5"},
    {VR_OFFSET, "offset", T_FLOAT64, CA_PARAMETER, VA_TUNABLE, IN_EXACT, 1, NO_VR, "0.1"},
    {VR_X, "x", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "1"},
    {VR_DER_X, "der(x)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_Y, "y", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_CALCULATED, 8, VR_N, NULL},
};

static const fmi3ValueReference STATES[] = {VR_X};
static const fmi3ValueReference DERIVATIVES[] = {VR_DER_X};

static void calculate(Instance *c) {
    double x = *f64(c, VR_X), scale = *f64(c, VR_GAIN_SCALE);
    double offset = *flag(c, VR_USE_OFFSET) ? *f64(c, VR_OFFSET) : 0.0;
    size_t k;
    *f64(c, VR_TIME) = fmu_time(c);
    *f64(c, VR_DER_X) = -x;
    for (k = 0; k < count(c, VR_Y); k++) f64(c, VR_Y)[k] = scale * f64(c, VR_GAINS)[k] * x + offset;
}

const ModelDef MODEL = {
    VARS, sizeof VARS / sizeof VARS[0], IF_ME | IF_CS,
    1, STATES, DERIVATIVES, 0, 0.001,
    calculate, NULL, NULL, NULL,
};
