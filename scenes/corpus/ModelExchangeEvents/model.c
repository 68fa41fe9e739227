/*
 * ModelExchangeEvents - a bouncing ball, Model Exchange only.
 *
 *   der(h) = v, der(v) = g (0 once the ball rests)
 *   state event: contact = h crosses zero with v < 0: v := -e v, bounces += 1;
 *                a bounce slower than 0.1 m/s puts the ball to rest
 *   time events: every period seconds from the start, sampled := h
 */
#include <math.h>

#include "corpus_model.h"

enum { VR_TIME, VR_H, VR_DER_H, VR_V, VR_DER_V, VR_G, VR_E, VR_PERIOD, VR_SAMPLED, VR_BOUNCES,
       VR_RESTING, VR_CONTACT };

static const VarDef VARS[] = {
    {VR_TIME, "time", T_FLOAT64, CA_INDEPENDENT, VA_CONTINUOUS, IN_NONE, 1, NO_VR, NULL},
    {VR_H, "h", T_FLOAT64, CA_OUTPUT, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "1"},
    {VR_DER_H, "der(h)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_V, "v", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_EXACT, 1, NO_VR, "0"},
    {VR_DER_V, "der(v)", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_G, "g", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "-9.81"},
    {VR_E, "e", T_FLOAT64, CA_PARAMETER, VA_TUNABLE, IN_EXACT, 1, NO_VR, "0.7"},
    {VR_PERIOD, "period", T_FLOAT64, CA_PARAMETER, VA_FIXED, IN_EXACT, 1, NO_VR, "0.25"},
    {VR_SAMPLED, "sampled", T_FLOAT64, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_BOUNCES, "bounces", T_INT32, CA_OUTPUT, VA_DISCRETE, IN_CALCULATED, 1, NO_VR, NULL},
    {VR_RESTING, "resting", T_BOOLEAN, CA_LOCAL, VA_DISCRETE, IN_EXACT, 1, NO_VR, "false"},
    {VR_CONTACT, "contact", T_FLOAT64, CA_LOCAL, VA_CONTINUOUS, IN_CALCULATED, 1, NO_VR, NULL},
};

static const fmi3ValueReference STATES[] = {VR_H, VR_V};
static const fmi3ValueReference DERIVATIVES[] = {VR_DER_H, VR_DER_V};

static void calculate(Instance *c) {
    int resting = *flag(c, VR_RESTING);
    *f64(c, VR_TIME) = fmu_time(c);
    *f64(c, VR_DER_H) = resting ? 0.0 : *f64(c, VR_V);
    *f64(c, VR_DER_V) = resting ? 0.0 : *f64(c, VR_G);
    *f64(c, VR_CONTACT) = resting ? 1.0 : *f64(c, VR_H);
}

static void indicators(Instance *c, double z[]) { z[0] = *f64(c, VR_CONTACT); }

static void event(Instance *c, fmi3Boolean *states_changed) {
    double t = fmu_time(c), period = *f64(c, VR_PERIOD), next;
    if (!*flag(c, VR_RESTING) && *f64(c, VR_H) <= 0.0 && *f64(c, VR_V) < 0.0) {
        double v = -*f64(c, VR_E) * *f64(c, VR_V);
        *f64(c, VR_H) = 0.0;
        *f64(c, VR_V) = v;
        if (v < 0.1) {
            *f64(c, VR_V) = 0.0;
            *flag(c, VR_RESTING) = fmi3True;
        }
        *i64(c, VR_BOUNCES) += 1;
        *states_changed = fmi3True;
        log_event(c, "bounce");
    }
    /* Time events: the first sample at the start, then one every period. */
    if (!next_event_time(c, &next)) {
        *f64(c, VR_SAMPLED) = *f64(c, VR_H);
        set_next_event_time(c, t + period);
    } else if (t >= next - 1e-9 * (1.0 + fabs(t))) {
        *f64(c, VR_SAMPLED) = *f64(c, VR_H);
        while (next <= t + 1e-9 * (1.0 + fabs(t))) next += period;
        set_next_event_time(c, next);
    }
}

const ModelDef MODEL = {
    VARS, sizeof VARS / sizeof VARS[0], IF_ME,
    2, STATES, DERIVATIVES, 1, 0.001,
    calculate, indicators, event, NULL,
};
