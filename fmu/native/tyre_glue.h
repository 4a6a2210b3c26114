/* The tyre model behind the FMI wrapper (fmi2_tyre.c): one implementation per model family
 * (glue_wheel.c: steady and transient; glue_swift.c: SWIFT). All return 0 on success. */
#ifndef TYRE_GLUE_H
#define TYRE_GLUE_H
#include <stddef.h>

typedef struct GlueWork GlueWork; /* per-instance work memory of the generated functions */

GlueWork *glue_alloc(void);
void glue_free(GlueWork *w);
/* model-specific checks of parameters q and inputs u; on failure a message naming the variable */
int glue_validate(const double *q, const double *u, char *msg, size_t n);
/* initial state x at inputs u, parameters q */
int glue_init(GlueWork *w, const double *u, const double *q, double *x, char *msg, size_t n);
/* advance x in place over h with u held; GLUE_OVER_BUDGET when the step needs more internal steps than its time
 * budget (proportional to h), x unchanged */
#define GLUE_OVER_BUDGET 2
int glue_step(GlueWork *w, double *x, const double *u, const double *q, double h);
/* outputs y at (x, u) */
int glue_out(GlueWork *w, const double *x, const double *u, const double *q, double *y);
/* dy = d out / d(x, u) * (dx, du), dxdot = d deriv / d(x, u) * (dx, du) at (x, u) */
int glue_dout(GlueWork *w, const double *x, const double *u, const double *q, const double *dx, const double *du,
              double *dy, double *dxdot);
/* model exchange (TYRE_HAS_ME): the state derivatives xdot and the TYRE_NZ event indicators z at (x, u) */
int glue_deriv(GlueWork *w, const double *x, const double *u, const double *q, double *xdot);
int glue_events(GlueWork *w, const double *x, const double *u, const double *q, double *z);
#endif
