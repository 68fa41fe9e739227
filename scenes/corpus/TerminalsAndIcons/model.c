/*
 * TerminalsAndIcons - a mass m on a spring c, pushed by the input force f:
 *   der(s) = v, der(v) = (f - c s) / m, power = f v.
 * Model Exchange and Co-Simulation; its flange terminal (s, f) and its icons
 * are in terminalsAndIcons/.
 */
#include "corpus_model.h"

enum { VR_TIME, VR_S, VR_DER_S, VR_V, VR_DER_V, VR_F, VR_M, VR_C, VR_POWER };

static const VarDef VARS[] = {
    {VR_TIME, "time", T_FLOAT64, CA_INDEPENDENT, VA_CONTINUOUS, IN_NONE, 1, NO_VR, NULL},
    {VR_S, "s", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "0.1"},
    {VR_DER_S, "der(s)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_V, "v", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "0"},
    {VR_DER_V, "der(v)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_F, "f", T_FLOAT64, CA_INPUT, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "0"},
    {VR_M, "m", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "1"},
    {VR_C, "c", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "10"},
    {VR_POWER, "power", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
};

static const fmi3ValueReference STATES[] = {VR_S, VR_V};
static const fmi3ValueReference DERIVATIVES[] = {VR_DER_S, VR_DER_V};

static void calculate(Instance *c) {
    double f = *f64(c, VR_F), v = *f64(c, VR_V);
    *f64(c, VR_TIME) = fmu_time(c);
    *f64(c, VR_DER_S) = v;
    *f64(c, VR_DER_V) = (f - *f64(c, VR_C) * *f64(c, VR_S)) / *f64(c, VR_M);
    *f64(c, VR_POWER) = f * v;
}

const ModelDef MODEL = {
    VARS, sizeof VARS / sizeof VARS[0], IF_ME | IF_CS,
    2, STATES, DERIVATIVES, 0, 0.0005,
    calculate, NULL, NULL, NULL,
};
