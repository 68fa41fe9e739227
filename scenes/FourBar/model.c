/*
 * FourBar - a planar four-bar linkage (double-wishbone suspension) in index-1
 * form, in SI units: angles in rad, loop forces in N (about 1e4), moment
 * balances in N m, loop accelerations in m/s^2.  Equations: fourbar.h.
 * FourBarScaled is the same model in kN and mm.
 */
#define FOURBAR_LENGTH_UNIT 1.0   /* m */
#define FOURBAR_FORCE_UNIT  1.0   /* N */
#include "fourbar.h"

FOURBAR_MODEL(1.0e4);
