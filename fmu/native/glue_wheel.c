/* Steady and transient tyre (mftyre.transient): the functions CasADi generated in tyre_model.c and tyre_start.c
 * (tyre_init). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "tyre_config.h"
#include "tyre_glue.h"
#include "tyre_model.h"
#include "tyre_start.h"

#define NFUN 6
typedef int (*WorkFn)(casadi_int *, casadi_int *, casadi_int *, casadi_int *);

struct GlueWork {
    const double *arg[8];
    double *res[4];
    casadi_int *iw;
    double *w;
};

GlueWork *glue_alloc(void) {
    WorkFn work[NFUN] = {tyre_init_work, tyre_step_work, tyre_out_work, tyre_dout_work, tyre_deriv_work,
                         tyre_events_work};
    casadi_int niw = 1, nw = 1;
    GlueWork *g = (GlueWork *)calloc(1, sizeof(GlueWork));
    if (!g) return NULL;
    for (int i = 0; i < NFUN; i++) {
        casadi_int a, r, iw, w;
        work[i](&a, &r, &iw, &w);
        if (iw > niw) niw = iw;
        if (w > nw) nw = w;
    }
    g->iw = (casadi_int *)calloc((size_t)niw, sizeof(casadi_int));
    g->w = (double *)calloc((size_t)nw, sizeof(double));
    if (!g->iw || !g->w) {
        glue_free(g);
        return NULL;
    }
    return g;
}

void glue_free(GlueWork *g) {
    if (!g) return;
    free(g->iw);
    free(g->w);
    free(g);
}

int glue_validate(const double *q, const double *u, char *msg, size_t n) {
    if (!(u[TYRE_U_P] > 0.0)) {
        snprintf(msg, n, "input p (inflation pressure) must be positive, got %g Pa", u[TYRE_U_P]);
        return 1;
    }
    /* the input policy's speed limits (TYRE_LIMITS, fmu.native_build.limit_definitions), as
     * mftyre.transient.WheelTyre applies mftyre.inputs.check_limits at every start and step */
    TYRE_LIMITS_REFUSE(u, msg, n);
    if (TYRE_NQ > 0 && !(q[0] >= 0.0)) {
        snprintf(msg, n, "parameter %s must be >= 0, got %g", TYRE_Q_NAMES[0], q[0]);
        return 1;
    }
    return 0;
}

int glue_init(GlueWork *g, const double *u, const double *q, double *x, char *msg, size_t n) {
    (void)msg;
    (void)n;
    g->arg[0] = u;
    g->arg[1] = q;
    g->res[0] = x;
    return tyre_init(g->arg, g->res, g->iw, g->w, 0);
}

int glue_step(GlueWork *g, double *x, const double *u, const double *q, double h) {
    double x_next[TYRE_NX > 0 ? TYRE_NX : 1];
    if (TYRE_NX == 0) return 0;
    g->arg[0] = x;
    g->arg[1] = u;
    g->arg[2] = q;
    g->arg[3] = &h;
    g->res[0] = x_next;
    if (tyre_step(g->arg, g->res, g->iw, g->w, 0)) return 1;
    for (int i = 0; i < TYRE_NX; i++) x[i] = x_next[i];
    return 0;
}

int glue_out(GlueWork *g, const double *x, const double *u, const double *q, double *y) {
    g->arg[0] = x;
    g->arg[1] = u;
    g->arg[2] = q;
    g->res[0] = y;
    return tyre_out(g->arg, g->res, g->iw, g->w, 0);
}

int glue_dout(GlueWork *g, const double *x, const double *u, const double *q, const double *dx, const double *du,
              double *dy, double *dxdot) {
    g->arg[0] = x;
    g->arg[1] = u;
    g->arg[2] = q;
    g->arg[3] = dx;
    g->arg[4] = du;
    g->res[0] = dy;
    g->res[1] = dxdot;
    return tyre_dout(g->arg, g->res, g->iw, g->w, 0);
}

int glue_deriv(GlueWork *g, const double *x, const double *u, const double *q, double *xdot) {
    g->arg[0] = x;
    g->arg[1] = u;
    g->arg[2] = q;
    g->res[0] = xdot;
    return tyre_deriv(g->arg, g->res, g->iw, g->w, 0);
}

int glue_events(GlueWork *g, const double *x, const double *u, const double *q, double *z) {
    g->arg[0] = x;
    g->arg[1] = u;
    g->arg[2] = q;
    g->res[0] = z;
    return tyre_events(g->arg, g->res, g->iw, g->w, 0);
}
