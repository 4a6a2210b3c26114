/* SWIFT tyre (swift.fmu_model): the rigid ring stepped over the road table built into tyre_config.h, with the
 * functions CasADi generated in tyre_model.c (swift_substep, swift_out) and tyre_start.c (swift_init, swift_residual,
 * swift_root). Mirrors
 * swift.fmu_model.SwiftWheel line by line: window placement, imposed axle height and spin, step splitting. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "tyre_config.h"
#include "tyre_glue.h"
#include "tyre_model.h"
#include "tyre_start.h"

#define NFUN 5
typedef int (*WorkFn)(casadi_int *, casadi_int *, casadi_int *, casadi_int *);

struct GlueWork {
    const double **arg;
    double **res;
    casadi_int *iw;
    double *w;
};

GlueWork *glue_alloc(void) {
    WorkFn work[NFUN] = {swift_init_work, swift_substep_work, swift_out_work, swift_residual_work,
                          swift_root_work};
    casadi_int narg = 8, nres = 4, niw = 1, nw = 1;
    GlueWork *g = (GlueWork *)calloc(1, sizeof(GlueWork));
    if (!g) return NULL;
    for (int i = 0; i < NFUN; i++) {
        casadi_int a, r, iw, w;
        work[i](&a, &r, &iw, &w);
        if (a > narg) narg = a;
        if (r > nres) nres = r;
        if (iw > niw) niw = iw;
        if (w > nw) nw = w;
    }
    g->arg = (const double **)calloc((size_t)narg, sizeof(double *));
    g->res = (double **)calloc((size_t)nres, sizeof(double *));
    g->iw = (casadi_int *)calloc((size_t)niw, sizeof(casadi_int));
    g->w = (double *)calloc((size_t)nw, sizeof(double));
    if (!g->arg || !g->res || !g->iw || !g->w) {
        glue_free(g);
        return NULL;
    }
    return g;
}

void glue_free(GlueWork *g) {
    if (!g) return;
    free(g->arg);
    free(g->res);
    free(g->iw);
    free(g->w);
    free(g);
}

/* first sample of the window around xb, clamped to the table (its ends are constant road) */
static long window_start(double xb) {
    double i0 = floor((xb - ROAD_X0) / ROAD_DX) - ROAD_WINDOW / 2;
    if (!(i0 > 0)) return 0;
    if (i0 > ROAD_N - ROAD_WINDOW) return ROAD_N - ROAD_WINDOW;
    return (long)i0;
}

/* The window arguments of the functions from position `first` on: the window's start x0w (kept in *x0w), the
 * grid and the interleaved (height, camber slope) pairs of the window around xb. */
static void set_window(GlueWork *g, int first, double xb, double *x0w) {
    long i0 = window_start(xb);
    *x0w = ROAD_X0 + i0 * ROAD_DX;
    g->arg[first] = x0w;
    g->arg[first + 1] = ROAD_GRID;
    g->arg[first + 2] = ROAD_H + 2 * i0;
}

int glue_validate(const double *q, const double *u, char *msg, size_t n) {
    if (!(u[TYRE_U_P] > 0.0)) {
        snprintf(msg, n, "input p (inflation pressure) must be positive, got %g Pa", u[TYRE_U_P]);
        return 1;
    }
    /* the sidewall stiffness and damping factors positive at this pressure (swift.ring.check_pressure) */
    double dpi = (u[TYRE_U_P] - SWIFT_P_NOM) / SWIFT_P_NOM;
    int stiffness = !(1.0 + SWIFT_P_STIFF * dpi > 0.0);
    if (stiffness || !(1.0 + SWIFT_P_DAMP * dpi > 0.0)) {
        const char *name = stiffness ? "SWIFT_PSTIFF" : "SWIFT_PDAMP", *what = stiffness ? "stiffness" : "damping";
        double coef = stiffness ? SWIFT_P_STIFF : SWIFT_P_DAMP;
        snprintf(msg, n, "input p (inflation pressure) = %g Pa gives a SWIFT sidewall %s factor 1 + %s dpi = %g <= 0 "
                 "(%s = %g, NOMPRES = %g Pa): a ring with negative %s is no tyre", u[TYRE_U_P], what, name,
                 1.0 + coef * dpi, name, coef, SWIFT_P_NOM, what);
        return 1;
    }
    if (!(q[TYRE_Q_MAX_STEP] > 0.0)) {
        snprintf(msg, n, "parameter max_step must be positive, got %g s", q[TYRE_Q_MAX_STEP]);
        return 1;
    }
    return 0;
}

int glue_init(GlueWork *g, const double *u, const double *q, double *x, char *msg, size_t n) {
    double x0w;
    /* the input policy's speed limits at the start (TYRE_LIMITS, fmu.native_build.limit_definitions), as
     * SwiftTyre.initial_state's mftyre.inputs.check_limits */
    TYRE_LIMITS_REFUSE(u, msg, n);
    g->arg[0] = u;
    g->arg[1] = q;
    set_window(g, 2, q[TYRE_Q_X_START], &x0w);
    g->res[0] = x;
    if (swift_init(g->arg, g->res, g->iw, g->w, 0)) {
        snprintf(msg, n, "the static equilibrium could not be evaluated");
        return 1;
    }
    for (int i = 0; i < TYRE_NX; i++)
        if (!isfinite(x[i])) {
#ifdef TYRE_U_Z
            snprintf(msg, n, "no static equilibrium found at the initial inputs (z = %g m, x_start = %g m)",
                     u[TYRE_U_Z], q[TYRE_Q_X_START]);
#else
            snprintf(msg, n, "no static equilibrium found at the initial inputs (Fz_in = %g N, x_start = %g m)",
                     u[TYRE_U_FZ_IN], q[TYRE_Q_X_START]);
#endif
            return 1;
        }
    /* the rules of swift.simulate.SwiftTyre.initial_state, with its messages, the window of the start as
     * swift_init's: the equilibrium equations' derivatives within SWIFT_EQUILIBRIUM_TOL (SWIFT_NO_EQUILIBRIUM), and
     * a root that is a rolling tyre (SwiftTyre.rolling_root_function, SWIFT_NO_ROLLING_ROOT) */
    double r[SWIFT_NEQ], facts[5], x0r;
    char start[256];
    int worst = 0;
    g->arg[0] = x;
    g->arg[1] = u;
    set_window(g, 2, q[TYRE_Q_X_START], &x0r);
    g->res[0] = r;
    if (swift_residual(g->arg, g->res, g->iw, g->w, 0)) {
        snprintf(msg, n, "the static equilibrium could not be checked");
        return 1;
    }
    for (int i = 0; i < SWIFT_NEQ; i++) /* the largest derivative, or the first that is not finite */
        if (!isfinite(r[i]) || fabs(r[i]) > fabs(r[worst])) {
            worst = i;
            if (!isfinite(r[i])) break;
        }
    snprintf(start, sizeof start, SWIFT_START_TEXT, SWIFT_START_VALUES(u, q));
    if (!(fabs(r[worst]) <= SWIFT_EQUILIBRIUM_TOL)) {
        snprintf(msg, n, SWIFT_NO_EQUILIBRIUM, start, SWIFT_NEWTON_STEPS, SWIFT_EQ_NAMES[worst], r[worst],
                 SWIFT_EQUILIBRIUM_TOL);
        return 1;
    }
    g->res[0] = facts;
    if (swift_root(g->arg, g->res, g->iw, g->w, 0)) {
        snprintf(msg, n, "the static equilibrium could not be checked");
        return 1;
    }
    if (facts[0] != 0.0) {
        snprintf(msg, n, SWIFT_NO_ROLLING_ROOT, start, facts[1], facts[2], facts[3], facts[4]);
        return 1;
    }
    return 0;
}

int glue_step(GlueWork *g, double *x, const double *u, const double *q, double h) {
    double x_next[TYRE_NX];
    /* the stepping rule of swift.fmu_model.internal_steps (its constants generated into tyre_config.h):
     * RK4 steps of at most max_step and never above SWIFT_MAX_RK4_STEP (stability of the parked tyre) */
    double n1 = ceil(h / fmin(q[TYRE_Q_MAX_STEP], SWIFT_MAX_RK4_STEP) - 1e-9);
    double n2 = ceil(fabs(u[TYRE_U_VX]) * h / SWIFT_MAX_TRAVEL);
    double nd = n1 > n2 ? n1 : n2;
    long n;
    /* the time budget of one call, proportional to the step: at most STEP_RATE_LIMIT internal steps per simulated
     * second (steps of 1 us; ~6 us of CPU each, so at most a few seconds of CPU per simulated second), never more
     * than SWIFT_MAX_STEPS_PER_CALL (~2 s of CPU); a step over budget (max_step far too small, |vx| far beyond any
     * vehicle, or a step too long) is refused */
    if (!(nd <= ceil(h * STEP_RATE_LIMIT) && nd <= SWIFT_MAX_STEPS_PER_CALL)) return GLUE_OVER_BUDGET;
    n = nd < 1 ? 1 : (long)nd;
#ifdef TYRE_U_Z /* axle height imposed; with the input load the axle moves (swift.fmu_model) */
    x[S_ZA] = u[TYRE_U_Z];
    x[S_VZA] = u[TYRE_U_VZ];
#endif
#ifndef TYRE_U_TORQUE /* rim speed imposed; with the input torque the rim spins freely (swift.fmu_model) */
    x[S_OMA] = u[TYRE_U_OMEGA];
#endif
    for (long k = 0; k < n; k++) {
        double dt = h / (double)n, x0w;
        g->arg[0] = x;
        g->arg[1] = u;
        g->arg[2] = &dt;
        set_window(g, 3, x[S_XB], &x0w);
        g->res[0] = x_next;
        if (swift_substep(g->arg, g->res, g->iw, g->w, 0)) return 1;
        for (int i = 0; i < TYRE_NX; i++) x[i] = x_next[i];
    }
    return 0;
}

int glue_out(GlueWork *g, const double *x, const double *u, const double *q, double *y) {
    double x0w;
    (void)q;
    g->arg[0] = x;
    g->arg[1] = u;
    set_window(g, 2, x[S_XB], &x0w);
    g->res[0] = y;
    return swift_out(g->arg, g->res, g->iw, g->w, 0);
}

int glue_dout(GlueWork *g, const double *x, const double *u, const double *q, const double *dx, const double *du,
              double *dy, double *dxdot) {
    (void)g, (void)x, (void)u, (void)q, (void)dx, (void)du, (void)dy, (void)dxdot;
    return 1; /* not provided (providesDirectionalDerivative = false) */
}

/* no model exchange (TYRE_HAS_ME 0): the step carries the contact solution and the road window (fmu/README.md) */
int glue_deriv(GlueWork *g, const double *x, const double *u, const double *q, double *xdot) {
    (void)g, (void)x, (void)u, (void)q, (void)xdot;
    return 1;
}

int glue_events(GlueWork *g, const double *x, const double *u, const double *q, double *z) {
    (void)g, (void)x, (void)u, (void)q, (void)z;
    return 1;
}
