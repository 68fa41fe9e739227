/*
 * FourBarScaled - the FourBar linkage with its variables rescaled: loop forces
 * in kN, moment balances in kN mm (= N m), loop accelerations in mm/s^2;
 * angles stay in rad.  Equations: fourbar.h (a link to FourBar/fourbar.h).
 * Every probe must give the same verdict for both scenes.
 */
#define FOURBAR_LENGTH_UNIT 1.0e-3   /* mm */
#define FOURBAR_FORCE_UNIT  1.0e3    /* kN */
#include "fourbar.h"

FOURBAR_MODEL(10.0);
