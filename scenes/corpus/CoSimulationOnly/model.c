/*
 * CoSimulationOnly - x'' = -k x - d x' + u, integrated inside fmi3DoStep.
 *
 * Co-Simulation only. x and v carry derivative attributes, but the
 * ModelStructure does not list <ContinuousStateDerivative>: FMI 3.0 §2.4.8
 * lets a Co-Simulation FMU leave them out. y = x, energy = (v^2 + k x^2) / 2.
 */
#include "corpus_model.h"

enum { VR_TIME, VR_U, VR_K, VR_D, VR_X, VR_DER_X, VR_V, VR_DER_V, VR_Y, VR_ENERGY };

static const VarDef VARS[] = {
    {VR_TIME, "time", T_FLOAT64, CA_INDEPENDENT, VA_CONTINUOUS, IN_NONE, 1, NO_VR, NULL},
    {VR_U, "u", T_FLOAT64, CA_INPUT, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "0"},
    {VR_K, "k", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "4"},
    {VR_D, "d", T_FLOAT64, CA_PARAMETER, VA_TUNABLE, IN_EXACT, 1, NO_VR, "0.4"},
    {VR_X, "x", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "1"},
    {VR_DER_X, "der(x)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_V, "v", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "0"},
    {VR_DER_V, "der(v)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_Y, "y", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_ENERGY, "energy", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
};

static const fmi3ValueReference STATES[] = {VR_X, VR_V};
static const fmi3ValueReference DERIVATIVES[] = {VR_DER_X, VR_DER_V};

static void calculate(Instance *c) {
    double x = *f64(c, VR_X), v = *f64(c, VR_V), k = *f64(c, VR_K);
    *f64(c, VR_TIME) = fmu_time(c);
    *f64(c, VR_DER_X) = v;
    *f64(c, VR_DER_V) = -k * x - *f64(c, VR_D) * v + *f64(c, VR_U);
    *f64(c, VR_Y) = x;
    *f64(c, VR_ENERGY) = 0.5 * (v * v + k * x * x);
}

const ModelDef MODEL = {
    VARS, sizeof VARS / sizeof VARS[0], IF_CS,
    2, STATES, DERIVATIVES, 0, 0.001,
    calculate, NULL, NULL, NULL,
};
