/*
 * ScheduledExecutionOnly - two model partitions, each run by
 * fmi3ActivateModelPartition on a tick of its periodic input Clock:
 *   fast (every 0.01 s): filtered += alpha (u - filtered), a clocked state
 *                        whose previous value is filteredBefore; y = filtered;
 *   slow (every 0.1 s):  slowTicks += 1.
 */
#include "corpus_model.h"

enum { VR_TIME, VR_FAST, VR_SLOW, VR_U, VR_ALPHA, VR_FILTERED, VR_BEFORE, VR_Y, VR_TICKS };

static const VarDef VARS[] = {
    {VR_TIME, "time", T_FLOAT64, CA_INDEPENDENT, VA_CONTINUOUS, IN_NONE, 1, NO_VR, NULL},
    {VR_FAST, "fast", T_CLOCK, CA_INPUT, VA_DISCRETE, IN_NONE, 1, NO_VR, "0.01"},
    {VR_SLOW, "slow", T_CLOCK, CA_INPUT, VA_DISCRETE, IN_NONE, 1, NO_VR, "0.1"},
    {VR_U, "u", T_FLOAT64, CA_INPUT, VA_DISCRETE, IN_EXACT, 1, NO_VR, "0"},
    {VR_ALPHA, "alpha", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "0.2"},
    {VR_FILTERED, "filtered", T_FLOAT64, CA_LOCAL, VA_DISCRETE, IN_EXACT, 1, NO_VR, "0"},
    {VR_BEFORE, "filteredBefore", T_FLOAT64, CA_LOCAL, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_Y, "y", T_FLOAT64, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_TICKS, "slowTicks", T_INT32, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
};

static void calculate(Instance *c) {
    *f64(c, VR_TIME) = fmu_time(c);
    *f64(c, VR_Y) = *f64(c, VR_FILTERED);
}

static void tick(Instance *c, fmi3ValueReference clock) {
    if (clock == VR_FAST) {
        double before = *f64(c, VR_FILTERED);
        *f64(c, VR_BEFORE) = before;
        *f64(c, VR_FILTERED) = before + *f64(c, VR_ALPHA) * (*f64(c, VR_U) - before);
    } else if (clock == VR_SLOW) {
        *i64(c, VR_TICKS) += 1;
    }
}

const ModelDef MODEL = {
    VARS, sizeof VARS / sizeof VARS[0], IF_SE,
    0, NULL, NULL, 0, 0.0,
    calculate, NULL, NULL, tick,
};
