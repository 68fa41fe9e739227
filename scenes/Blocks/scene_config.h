/* Blocks: the default N = 30 (scenes/Blocks/model.c) needs tables of 32 entries. */
#ifndef FMU_MAX_VARS
#define FMU_MAX_VARS 32
#endif
