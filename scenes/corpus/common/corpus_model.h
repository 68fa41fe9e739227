/*
 * corpus_model.h - the interface between corpus_fmu.c (every function of
 * fmi3Functions.h, for Model Exchange, Co-Simulation and Scheduled Execution)
 * and one corpus model (scenes/corpus/<Name>/model.c).
 *
 * The corpus models are ordinary FMI 3.0 FMUs that do not use the fmi-ls-dae
 * layer. A model file defines `const ModelDef MODEL`: a table of its
 * variables, written as in its modelDescription.xml (value reference, type,
 * causality, variability, effective initial, element count, start values),
 * its continuous states, and a few callbacks that compute the equations.
 * Everything else (values, start values, the state machine and which
 * fmi3Set* calls each state allows, events, Co-Simulation steps, clocks)
 * lives in corpus_fmu.c.
 */
#ifndef CORPUS_MODEL_H
#define CORPUS_MODEL_H

#include <stddef.h>

#include "fmi3Functions.h"

#define NO_VR ((fmi3ValueReference)0xFFFFFFFFu)

typedef enum {
    T_FLOAT32, T_FLOAT64, T_INT8, T_UINT8, T_INT16, T_UINT16, T_INT32, T_UINT32,
    T_INT64, T_UINT64, T_BOOLEAN, T_STRING, T_BINARY, T_CLOCK, T_ENUMERATION
} VarType;

typedef enum {
    CA_PARAMETER, CA_CALCULATED_PARAMETER, CA_STRUCTURAL_PARAMETER,
    CA_INPUT, CA_OUTPUT, CA_LOCAL, CA_INDEPENDENT
} Causality;

typedef enum { VA_CONSTANT, VA_FIXED, VA_TUNABLE, VA_DISCRETE, VA_CONTINUOUS } Variability;

/* The effective initial (the declared one, else the FMI 3.0 default); IN_NONE where FMI
 * allows none (the independent variable, Clocks). */
typedef enum { IN_NONE, IN_EXACT, IN_APPROX, IN_CALCULATED } Initial;

typedef struct {
    fmi3ValueReference vr;
    const char *name;
    VarType type;
    Causality causality;
    Variability variability;
    Initial initial;
    size_t size;                 /* element count; with size_vr, the capacity (largest count) */
    fmi3ValueReference size_vr;  /* NO_VR, or the UInt64 structural parameter that is the
                                    count of a one-dimensional array */
    const char *start;           /* the start values as in the XML (space-separated, Binary in
                                    hex; a single value is used for every element), or NULL */
} VarDef;

#define IF_ME 1
#define IF_CS 2
#define IF_SE 4

typedef struct Instance Instance;

typedef struct {
    const VarDef *vars;
    size_t nvars;
    int interfaces;                         /* IF_ME | IF_CS | IF_SE */
    size_t nx;                              /* continuous states, scalar Float64 */
    const fmi3ValueReference *states;       /* nx value references, in ModelStructure order */
    const fmi3ValueReference *derivatives;  /* their derivatives, same order */
    size_t nz;                              /* event indicators */
    double cs_step;                         /* internal step of fmi3DoStep (Co-Simulation) */
    /* Compute every calculated variable (derivatives, outputs, calculated parameters) from
     * time, the states, inputs and parameters. Called before values are read. */
    void (*calculate)(Instance *c);
    /* The event indicators (nz values); NULL when nz is 0. */
    void (*event_indicators)(Instance *c, double z[]);
    /* Event Mode, after initialisation and at every state or time event: update discrete
     * variables, reinitialise states (set *states_changed), schedule the next time event
     * with set_next_event_time. May be NULL. */
    void (*event)(Instance *c, fmi3Boolean *states_changed);
    /* A tick of an input Clock: a model partition (Scheduled Execution) or an input Clock
     * set by the importer in Event Mode. May be NULL. */
    void (*tick)(Instance *c, fmi3ValueReference clock);
} ModelDef;

extern const ModelDef MODEL;

/* For the model: values by value reference (every element of an array, row-major). */
double *f64(Instance *c, fmi3ValueReference vr);             /* Float32 and Float64 */
fmi3Int64 *i64(Instance *c, fmi3ValueReference vr);          /* IntN and Enumeration */
fmi3UInt64 *u64(Instance *c, fmi3ValueReference vr);         /* UIntN */
fmi3Boolean *flag(Instance *c, fmi3ValueReference vr);       /* Boolean and Clock */
const char *string_value(Instance *c, fmi3ValueReference vr);
const fmi3Byte *binary_value(Instance *c, fmi3ValueReference vr, size_t *size);
fmi3Status set_string(Instance *c, fmi3ValueReference vr, const char *value);
size_t count(Instance *c, fmi3ValueReference vr);             /* current element count */
double fmu_time(Instance *c);
void set_next_event_time(Instance *c, double t);              /* a time event at t */
fmi3Boolean next_event_time(Instance *c, double *t);          /* the scheduled one, if any */
void clear_next_event_time(Instance *c);
void tick_output_clock(Instance *c, fmi3ValueReference clock);
void log_event(Instance *c, const char *message);

#endif
