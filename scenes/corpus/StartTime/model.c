/*
 * StartTime - der(x) = (sin(time) + step - x) / tau, y = x + step, with
 * step = stepHeight once time >= stepTime (a time event), else 0.
 * The default experiment starts at t = 10, so the step at 11 happens one second
 * after the start, and an importer that starts at 0 sees something else.
 * Model Exchange and Co-Simulation.
 */
#include <math.h>

#include "corpus_model.h"

enum { VR_TIME, VR_X, VR_DER_X, VR_TAU, VR_STEP_TIME, VR_STEP_HEIGHT, VR_STEPPED, VR_Y };

static const VarDef VARS[] = {
    {VR_TIME, "time", T_FLOAT64, CA_INDEPENDENT, VA_CONTINUOUS, IN_NONE, 1, NO_VR, NULL},
    {VR_X, "x", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "0"},
    {VR_DER_X, "der(x)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_TAU, "tau", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "0.5"},
    {VR_STEP_TIME, "stepTime", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "11"},
    {VR_STEP_HEIGHT, "stepHeight", T_FLOAT64, CA_PARAMETER, VA_TUNABLE, IN_EXACT, 1, NO_VR, "2"},
    {VR_STEPPED, "stepped", T_BOOLEAN, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_Y, "y", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
};

static const fmi3ValueReference STATES[] = {VR_X};
static const fmi3ValueReference DERIVATIVES[] = {VR_DER_X};

static void calculate(Instance *c) {
    double t = fmu_time(c), step = *flag(c, VR_STEPPED) ? *f64(c, VR_STEP_HEIGHT) : 0.0;
    *f64(c, VR_TIME) = t;
    *f64(c, VR_DER_X) = (sin(t) + step - *f64(c, VR_X)) / *f64(c, VR_TAU);
    *f64(c, VR_Y) = *f64(c, VR_X) + step;
}

static void event(Instance *c, fmi3Boolean *states_changed) {
    double t = fmu_time(c), at = *f64(c, VR_STEP_TIME);
    (void)states_changed;
    if (!*flag(c, VR_STEPPED) && t >= at - 1e-9 * (1.0 + fabs(at))) {
        *flag(c, VR_STEPPED) = fmi3True;
        clear_next_event_time(c);
        log_event(c, "step");
    } else if (!*flag(c, VR_STEPPED)) {
        set_next_event_time(c, at);
    }
}

const ModelDef MODEL = {
    VARS, sizeof VARS / sizeof VARS[0], IF_ME | IF_CS,
    1, STATES, DERIVATIVES, 0, 0.001,
    calculate, NULL, event, NULL,
};
