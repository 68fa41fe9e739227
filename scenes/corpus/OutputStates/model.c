/*
 * OutputStates - the van der Pol oscillator with both states as outputs, written as the
 * Reference FMUs write such outputs: <Output dependencies=""> (whether an output that is a
 * state should depend on itself is the open question of Reference-FMUs issue 657).
 *
 *   der(x0) = x1
 *   der(x1) = mu (1 - x0^2) x1 - x0 + u
 *
 * Model Exchange only; a continuous input u and a fixed parameter mu.
 */
#include "corpus_model.h"

enum { VR_TIME, VR_X0, VR_DER_X0, VR_X1, VR_DER_X1, VR_MU, VR_U };

static const VarDef VARS[] = {
    {VR_TIME, "time", T_FLOAT64, CA_INDEPENDENT, VA_CONTINUOUS, IN_NONE, 1, NO_VR, NULL},
    {VR_X0, "x0", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "2"},
    {VR_DER_X0, "der(x0)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_X1, "x1", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "0"},
    {VR_DER_X1, "der(x1)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_MU, "mu", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "1"},
    {VR_U, "u", T_FLOAT64, CA_INPUT, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "0"},
};

static const fmi3ValueReference STATES[] = {VR_X0, VR_X1};
static const fmi3ValueReference DERIVATIVES[] = {VR_DER_X0, VR_DER_X1};

static void calculate(Instance *c) {
    double x0 = *f64(c, VR_X0), x1 = *f64(c, VR_X1), mu = *f64(c, VR_MU);
    *f64(c, VR_TIME) = fmu_time(c);
    *f64(c, VR_DER_X0) = x1;
    *f64(c, VR_DER_X1) = mu * (1.0 - x0 * x0) * x1 - x0 + *f64(c, VR_U);
}

const ModelDef MODEL = {
    VARS, sizeof VARS / sizeof VARS[0], IF_ME,
    2, STATES, DERIVATIVES, 0, 0.001,
    calculate, NULL, NULL, NULL,
};
