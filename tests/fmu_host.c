/* A plain C host of the mftyre FMU binaries (tests/test_fmu_variants.py, benchmarks/bench_fmu.py): loads one
 * binary (dlopen, or LoadLibrary when compiled for Windows with MinGW and run under Wine), runs N instances side by
 * side for STEPS steps of H = 1 ms with varying inputs and prints every instance's outputs after the last step
 * (%.17g) and the sums of Fx over the run, then the time per step of one instance (the best chunk of CHUNK steps
 * over REPEAT runs: the one least disturbed by other work on a shared machine).
 *
 * FMI 2 or 3, co-simulation (the FMU's doStep) or model exchange (this host integrates the states with explicit
 * Euler steps of H: set time, states, inputs; get derivatives and event indicators; completed integrator step).
 * One step of an instance: CS set vx, vy, omega, doStep, get Fx; ME get derivatives and event indicators, set time,
 * states and vx, vy, omega, completed integrator step, get Fx.
 *
 *   host LIB FMI(2|3) IFACE(cs|me) GUID N STEPS REPEAT NX NZ VR_VX VR_VY VR_OMEGA NY VR_Y1 ... VR_YNY
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _WIN32
#include <windows.h>
static void *open_library(const char *path) { return (void *)LoadLibraryA(path); }
static void *symbol(void *lib, const char *name) { return (void *)GetProcAddress((HMODULE)lib, name); }
static double now(void) {
    LARGE_INTEGER f, t;
    QueryPerformanceFrequency(&f);
    QueryPerformanceCounter(&t);
    return (double)t.QuadPart / (double)f.QuadPart;
}
#else
#include <dlfcn.h>
#include <time.h>
static void *open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(void *lib, const char *name) { return dlsym(lib, name); }
static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}
#endif
#include "fmi2Functions.h"
#include "fmi3Functions.h"

#define MAXN 8
#define MAXY 64
#define H 1e-3

static void log2_(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c, fmi2String f, ...) {
    (void)e, (void)n, (void)c;
    if (s >= fmi2Error) fprintf(stderr, "FMU: %s\n", f);
}
static void log3_(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m) {
    (void)e, (void)c;
    if (s >= fmi3Error) fprintf(stderr, "FMU: %s\n", m);
}

#define LOAD(name)                                                                                                 \
    name##TYPE *name = (name##TYPE *)symbol(lib, #name);                                                           \
    if (!name) {                                                                                                   \
        fprintf(stderr, "no symbol %s\n", #name);                                                                  \
        exit(3);                                                                                                   \
    }
#define CHECK(call)                                                                                                \
    if ((call) > 1) {                                                                                              \
        fprintf(stderr, "failed: %s\n", #call);                                                                    \
        exit(4);                                                                                                   \
    }

static int n, steps, repeat, nx, nz, ny, me;
static unsigned vr_in[3], vr_y[MAXY];
static double y[MAXN][MAXY], fx_sum[MAXN];
#define CHUNK 250
static double best_chunk = 1e30, chunk_start;

static void chunk_done(int k) { /* after step k of every instance */
    if (k % CHUNK == 0) {
        double t = now();
        if (t - chunk_start < best_chunk) best_chunk = t - chunk_start;
        chunk_start = t;
    }
}

static void inputs(int i, int k, double u[3]) { /* vx, vy, omega of instance i at step k */
    double t = k * H, vx = 10.0 + 3.0 * i;
    u[0] = vx;
    u[1] = 0.3 * (i + 1) * sin(6.0 * t);
    u[2] = vx / 0.305 * (1.0 + 0.05 * sin(4.0 * t + i));
}

static double run2(void *lib, const char *guid) {
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2SetReal) LOAD(fmi2GetReal) LOAD(fmi2FreeInstance)
    LOAD(fmi2Terminate)
    fmi2CallbackFunctions cb = {log2_, calloc, free, NULL, NULL};
    fmi2Component c[MAXN];
    double x[MAXN][8], dx[8], z[8], u[3], t0;
    for (int i = 0; i < n; i++) {
        c[i] = fmi2Instantiate("tyre", me ? fmi2ModelExchange : fmi2CoSimulation, guid, "", &cb, fmi2False,
                               fmi2False);
        if (!c[i]) exit(5);
        inputs(i, 0, u);
        CHECK(fmi2SetupExperiment(c[i], fmi2False, 0, 0, fmi2False, 0))
        CHECK(fmi2EnterInitializationMode(c[i]))
        CHECK(fmi2SetReal(c[i], vr_in, 3, u))
        CHECK(fmi2ExitInitializationMode(c[i]))
        fx_sum[i] = 0;
    }
    t0 = now();
    if (me) {
        LOAD(fmi2NewDiscreteStates) LOAD(fmi2EnterContinuousTimeMode) LOAD(fmi2SetTime)
        LOAD(fmi2SetContinuousStates) LOAD(fmi2GetContinuousStates) LOAD(fmi2GetDerivatives)
        LOAD(fmi2GetEventIndicators) LOAD(fmi2CompletedIntegratorStep)
        for (int i = 0; i < n; i++) {
            fmi2EventInfo info;
            CHECK(fmi2NewDiscreteStates(c[i], &info))
            CHECK(fmi2EnterContinuousTimeMode(c[i]))
            CHECK(fmi2GetContinuousStates(c[i], x[i], nx))
        }
        t0 = chunk_start = now();
        for (int k = 1; k <= steps; chunk_done(k++))
            for (int i = 0; i < n; i++) {
                fmi2Boolean enter, stop;
                CHECK(fmi2GetDerivatives(c[i], dx, nx))
                CHECK(fmi2GetEventIndicators(c[i], z, nz))
                for (int j = 0; j < nx; j++) x[i][j] += H * dx[j];
                inputs(i, k, u);
                CHECK(fmi2SetTime(c[i], k * H))
                CHECK(fmi2SetContinuousStates(c[i], x[i], nx))
                CHECK(fmi2SetReal(c[i], vr_in, 3, u))
                CHECK(fmi2CompletedIntegratorStep(c[i], fmi2True, &enter, &stop))
                CHECK(fmi2GetReal(c[i], vr_y, 1, y[i]))
                fx_sum[i] += y[i][0];
            }
    } else {
        LOAD(fmi2DoStep)
        chunk_start = now();
        for (int k = 1; k <= steps; chunk_done(k++))
            for (int i = 0; i < n; i++) {
                inputs(i, k - 1, u);
                CHECK(fmi2SetReal(c[i], vr_in, 3, u))
                CHECK(fmi2DoStep(c[i], (k - 1) * H, H, fmi2True))
                CHECK(fmi2GetReal(c[i], vr_y, 1, y[i]))
                fx_sum[i] += y[i][0];
            }
    }
    t0 = now() - t0;
    for (int i = 0; i < n; i++) {
        CHECK(fmi2GetReal(c[i], vr_y, ny, y[i]))
        fmi2Terminate(c[i]);
        fmi2FreeInstance(c[i]);
    }
    return t0;
}

static double run3(void *lib, const char *guid) {
    LOAD(fmi3InstantiateCoSimulation) LOAD(fmi3InstantiateModelExchange) LOAD(fmi3EnterInitializationMode)
    LOAD(fmi3ExitInitializationMode) LOAD(fmi3SetFloat64) LOAD(fmi3GetFloat64) LOAD(fmi3FreeInstance)
    LOAD(fmi3Terminate)
    fmi3Instance c[MAXN];
    double x[MAXN][8], dx[8], z[8], u[3], t0;
    for (int i = 0; i < n; i++) {
        c[i] = me ? fmi3InstantiateModelExchange("tyre", guid, "", fmi3False, fmi3False, NULL, log3_)
                  : fmi3InstantiateCoSimulation("tyre", guid, "", fmi3False, fmi3False, fmi3False, fmi3False, NULL,
                                                0, NULL, log3_, NULL);
        if (!c[i]) exit(5);
        inputs(i, 0, u);
        CHECK(fmi3EnterInitializationMode(c[i], fmi3False, 0, 0, fmi3False, 0))
        CHECK(fmi3SetFloat64(c[i], vr_in, 3, u, 3))
        CHECK(fmi3ExitInitializationMode(c[i]))
        fx_sum[i] = 0;
    }
    t0 = now();
    if (me) {
        LOAD(fmi3UpdateDiscreteStates) LOAD(fmi3EnterContinuousTimeMode) LOAD(fmi3SetTime)
        LOAD(fmi3SetContinuousStates) LOAD(fmi3GetContinuousStates) LOAD(fmi3GetContinuousStateDerivatives)
        LOAD(fmi3GetEventIndicators) LOAD(fmi3CompletedIntegratorStep)
        for (int i = 0; i < n; i++) {
            fmi3Boolean a, b, cc, d, e;
            double next;
            CHECK(fmi3UpdateDiscreteStates(c[i], &a, &b, &cc, &d, &e, &next))
            CHECK(fmi3EnterContinuousTimeMode(c[i]))
            CHECK(fmi3GetContinuousStates(c[i], x[i], nx))
        }
        t0 = chunk_start = now();
        for (int k = 1; k <= steps; chunk_done(k++))
            for (int i = 0; i < n; i++) {
                fmi3Boolean enter, stop;
                CHECK(fmi3GetContinuousStateDerivatives(c[i], dx, nx))
                CHECK(fmi3GetEventIndicators(c[i], z, nz))
                for (int j = 0; j < nx; j++) x[i][j] += H * dx[j];
                inputs(i, k, u);
                CHECK(fmi3SetTime(c[i], k * H))
                CHECK(fmi3SetContinuousStates(c[i], x[i], nx))
                CHECK(fmi3SetFloat64(c[i], vr_in, 3, u, 3))
                CHECK(fmi3CompletedIntegratorStep(c[i], fmi3True, &enter, &stop))
                CHECK(fmi3GetFloat64(c[i], vr_y, 1, y[i], 1))
                fx_sum[i] += y[i][0];
            }
    } else {
        LOAD(fmi3EnterStepMode) LOAD(fmi3DoStep)
        for (int i = 0; i < n; i++) CHECK(fmi3EnterStepMode(c[i]))
        chunk_start = now();
        for (int k = 1; k <= steps; chunk_done(k++))
            for (int i = 0; i < n; i++) {
                fmi3Boolean event, stop, early;
                double last;
                inputs(i, k - 1, u);
                CHECK(fmi3SetFloat64(c[i], vr_in, 3, u, 3))
                CHECK(fmi3DoStep(c[i], (k - 1) * H, H, fmi3True, &event, &stop, &early, &last))
                CHECK(fmi3GetFloat64(c[i], vr_y, 1, y[i], 1))
                fx_sum[i] += y[i][0];
            }
    }
    t0 = now() - t0;
    for (int i = 0; i < n; i++) {
        CHECK(fmi3GetFloat64(c[i], vr_y, ny, y[i], ny))
        fmi3Terminate(c[i]);
        fmi3FreeInstance(c[i]);
    }
    return t0;
}

int main(int argc, char **argv) {
    void *lib;
    int fmi;
    double best = 1e30;
    if (argc < 14) return 1;
    fmi = atoi(argv[2]);
    me = strcmp(argv[3], "me") == 0;
    n = atoi(argv[5]), steps = atoi(argv[6]), repeat = atoi(argv[7]), nx = atoi(argv[8]), nz = atoi(argv[9]);
    for (int j = 0; j < 3; j++) vr_in[j] = (unsigned)atoi(argv[10 + j]);
    ny = atoi(argv[13]);
    if (n > MAXN || ny > MAXY || ny < 1 || argc < 14 + ny || nx > 8 || nz > 8) return 1;
    for (int j = 0; j < ny; j++) vr_y[j] = (unsigned)atoi(argv[14 + j]);
    lib = open_library(argv[1]);
    if (!lib) {
        fprintf(stderr, "cannot load %s\n", argv[1]);
        return 2;
    }
    for (int r = 0; r < repeat; r++) {
        double t = fmi == 3 ? run3(lib, argv[4]) : run2(lib, argv[4]);
        if (t < best) best = t;
    }
    for (int i = 0; i < n; i++) {
        printf("instance %d fx_sum %.17g y", i, fx_sum[i]);
        for (int j = 0; j < ny; j++) printf(" %.17g", y[i][j]);
        printf("\n");
    }
    printf("us_per_step %.4f\n", 1e6 * (steps >= CHUNK ? best_chunk / CHUNK : best / steps) / n);
    return 0;
}
