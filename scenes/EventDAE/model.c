/*
 * EventDAE - a DAE with one state event that changes a residual and one time event
 * (README.md gives the analytic solution).
 *
 *   der(x) = -w
 *        0 = w - k*x - b                 (g)
 *        y = w
 *        z = (w - b)/k - s(k)            (event indicator; x - s(k) at consistent points)
 *
 * k and b are discrete variables the FMU changes in fmi3UpdateDiscreteStates:
 *   state event: k = 1 -> 3 when z <= 0, i.e. x falls to 0.5 (s(1) = 0.5); and back to 1 when
 *                z >= 0 while k = 3 (s(3) = 1.5: a hysteresis relay; x never rises again);
 *   time event:  b = 0 -> 0.5 at t = 0.75 (announced as nextEventTime until then).
 * The hook decides with the same z the importer sees (from its w in DAE mode), so the event
 * it located is the event that happens.
 * EVENTDAE_TERMINATE (a -D define): the time event asks to end the simulation
 * (terminateSimulation), for the simulation's handling of it.
 * DEFECT_STALE_TIME_EVENT: once the state event has switched k (and x < 0.75), every event
 * announces nextEventTime = t - 0.05, a time already past (next-event-time-behind-during-
 * simulation: only the simulation reaches the state event).
 */
#include "dae_model.h"

#define NX 1
#define NW 1
#define NU 0
#define NY 1

#define K 0                 /* d[K]: the gain k */
#define B 1                 /* d[B]: the offset b */
#define K_LOW 1.0
#define K_HIGH 3.0
#define SWITCH_DOWN 0.5     /* s(1) */
#define SWITCH_UP 1.5       /* s(3) */
#define T_EVENT 0.75
#define B_AFTER 0.5

static double indicator(const double w[], const double d[]) {
    return (w[0] - d[B]) / d[K] - (d[K] == K_LOW ? SWITCH_DOWN : SWITCH_UP);
}

static void eval(double t, const double x[], const double w[], const double u[],
                 const double d[], double der[], double res[], double y[]) {
    (void)t; (void)u;
    der[0] = -w[0];
    res[0] = w[0] - d[K] * x[0] - d[B];
    y[0] = w[0];
}

static void partials(double t, const double x[], const double w[], const double u[],
                     const double d[], double J[]) {
    (void)t; (void)x; (void)w; (void)u;
    D_DER_W(0, 0) = -1.0;
    D_RES_X(0, 0) = -d[K];
    D_RES_W(0, 0) = 1.0;
    D_OUT_W(0, 0) = 1.0;
}

static void indicators(double t, const double x[], const double w[], const double u[],
                       const double d[], double z[]) {
    (void)t; (void)x; (void)u;
    z[0] = indicator(w, d);
}

static void event(double t, double x[], const double w[], const double u[], double d[],
                  ModelEvent *ev) {
    const double z = indicator(w, d);
    (void)x; (void)u;
    if (d[K] == K_LOW && z <= 0.0) d[K] = K_HIGH;
    else if (d[K] == K_HIGH && z >= 0.0) d[K] = K_LOW;
    if (d[B] == 0.0 && t >= T_EVENT - 1e-12) d[B] = B_AFTER;
#ifdef EVENTDAE_TERMINATE
    if (d[B] == B_AFTER) ev->terminate = fmi3True;   /* the run ends at the time event */
#endif
    if (d[B] == 0.0) {
        ev->next_time_defined = fmi3True;
        ev->next_time = T_EVENT;
    }
#ifdef DEFECT_STALE_TIME_EVENT
    if (d[K] == K_HIGH && x[0] < 0.75) {   /* after the state event: a time event past */
        ev->next_time_defined = fmi3True;
        ev->next_time = t - 0.05;
    }
#endif
}

const ModelDef MODEL = {
    .nx = NX, .nw = NW, .nu = NU, .ny = NY,
    .vr_time = 0, .vr_enable = 9, .enable_tunable = fmi3True,
    .vr_x   = {1},   .vr_der = {2},
    .vr_w   = {3},   .vr_res = {5},
    .vr_y   = {4},
    .x_start = {1.0}, .w_start = {1.0},
    .x_nominal = {1.0}, .w_nominal = {1.0},
    .nd = 2, .nz = 1,
    .vr_d = {7, 8}, .vr_z = {6},
    .d_start = {K_LOW, 0.0},
    .eval_discrete = eval, .partials_discrete = partials,
    .indicators = indicators, .event = event,
};
