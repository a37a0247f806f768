/*
 * Compiled hybrid stepper for one plant mode: ROS3P Rosenbrock integration
 * with error control, dense (Hermite) output on a fixed grid, and guard
 * checking after every accepted step.
 *
 * Linked with CasADi-generated C for the mode's functions:
 *   kf (xs, t, P) -> f      right-hand side (scaled states)
 *   kj (xs, t, P) -> df/dxs (dense nx x nx, column major)
 *   kt (xs, t, P) -> df/dt
 *   kg (xs, t, P) -> g      guards (mode valid while g > 0)
 *   ko (xs, t, P) -> y      output signals
 *   kd (xs, t, P) -> (g, selector, dg/dt)   guards at an event, for the mode cascade
 *   kp (xs, t, P) -> xs     state projected onto the mode's constraints (rigid links, held current)
 *
 * ROS3P: J. Lang and J. Verwer, BIT 41 (2001) 731-738, order 3, A-stable,
 * embedded order 2.  Coefficients in the transformed form of Hairer & Wanner.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef long long int cint;
/* each generated CasADi function NAME comes with its work-size query NAME_work */
#define CASADI_FN(name) \
    int name(const double** arg, double** res, cint* iw, double* w, int mem); \
    int name##_work(cint* sz_arg, cint* sz_res, cint* sz_iw, cint* sz_w);
CASADI_FN(kf) CASADI_FN(kj) CASADI_FN(kt) CASADI_FN(kg) CASADI_FN(ko) CASADI_FN(kd) CASADI_FN(kp)
#undef CASADI_FN

#define NMAX 64
#define GMAX 64
/* interface version of the kiln_* entry points: kilnctl.model.stepper checks it before any call */
#define KILN_ABI 4
cint kf_n_in(void); cint kj_n_in(void); cint kt_n_in(void); cint kg_n_in(void);
cint ko_n_in(void); cint kd_n_in(void); cint kp_n_in(void);
cint kd_n_out(void);
/* A guard has crossed when it is below -guard_eps (an argument of kiln_run, defined once in Python:
   kilnctl.model.stepper.GUARD_EPS; guards are scaled to order one), so a guard that starts on its
   boundary does not fire on round-off or on integration error below the absolute tolerance. */

static const double GAM = 7.886751345948129e-01;
static const double A21 = 1.267949192431123, A31 = 1.267949192431123, A32 = 0.0;
static const double C21 = -1.607695154586736, C31 = -3.464101615137755, C32 = -1.732050807568877;
static const double M1 = 2.0, M2 = 5.773502691896258e-01, M3 = 4.226497308103742e-01;
static const double E1 = 2.0 - 2.113248654051871, E2 = 5.773502691896258e-01 - 1.0, E3 = 0.0;
static const double AL2 = 1.0, AL3 = 1.0;
static const double D1 = 7.886751345948129e-01, D2 = -2.113248654051871e-01, D3 = -1.077350269189626;

typedef struct {
    const double* P;
    cint iw[4096];
    double w[65536];
    const double* arg[64];
    double* res[64];
} ctx_t;

static int call3(int (*fn)(const double**, double**, cint*, double*, int), ctx_t* c,
                 const double* x, double t, double* out) {
    c->arg[0] = x; c->arg[1] = &t; c->arg[2] = c->P;
    c->res[0] = out;
    return fn(c->arg, c->res, c->iw, c->w, 0);
}

/* LU with partial pivoting of an n x n column-major matrix, in place. */
static int lu(int n, double* A, int* piv) {
    for (int k = 0; k < n; k++) {
        int p = k; double best = fabs(A[k + k * n]);
        for (int i = k + 1; i < n; i++) if (fabs(A[i + k * n]) > best) { best = fabs(A[i + k * n]); p = i; }
        if (best == 0.0) return -1;
        piv[k] = p;
        if (p != k) for (int j = 0; j < n; j++) { double t = A[k + j * n]; A[k + j * n] = A[p + j * n]; A[p + j * n] = t; }
        for (int i = k + 1; i < n; i++) {
            A[i + k * n] /= A[k + k * n];
            double l = A[i + k * n];
            if (l != 0.0) for (int j = k + 1; j < n; j++) A[i + j * n] -= l * A[k + j * n];
        }
    }
    return 0;
}

static void lusolve(int n, const double* A, const int* piv, double* b) {
    for (int k = 0; k < n; k++) { int p = piv[k]; if (p != k) { double t = b[k]; b[k] = b[p]; b[p] = t; } }
    for (int i = 0; i < n; i++) for (int j = 0; j < i; j++) b[i] -= A[i + j * n] * b[j];
    for (int i = n - 1; i >= 0; i--) { for (int j = i + 1; j < n; j++) b[i] -= A[i + j * n] * b[j]; b[i] /= A[i + i * n]; }
}

/* Hermite cubic between (t0, x0, f0) and (t1, x1, f1) at t. */
static void hermite(int n, double t0, const double* x0, const double* f0, double t1, const double* x1,
                    const double* f1, double t, double* out) {
    double h = t1 - t0, s = (t - t0) / h;
    double h00 = (1 + 2 * s) * (1 - s) * (1 - s), h10 = s * (1 - s) * (1 - s);
    double h01 = s * s * (3 - 2 * s), h11 = s * s * (s - 1);
    for (int i = 0; i < n; i++) out[i] = h00 * x0[i] + h10 * h * f0[i] + h01 * x1[i] + h11 * h * f1[i];
}

/* One ROS3P step from (t, x) with size h: x1 and the error estimate err (vector). */
static int ros_step(ctx_t* c, int n, double t, const double* x, const double* f0, const double* J,
                    const double* ft, double h, double* x1, double* errv, double* Wbuf, int* piv) {
    double u1[NMAX], u2[NMAX], u3[NMAX], xs[NMAX], fs[NMAX];
    for (int j = 0; j < n; j++) for (int i = 0; i < n; i++)
        Wbuf[i + j * n] = (i == j ? 1.0 / (h * GAM) : 0.0) - J[i + j * n];
    if (lu(n, Wbuf, piv)) return -1;
    for (int i = 0; i < n; i++) u1[i] = f0[i] + h * D1 * ft[i];
    lusolve(n, Wbuf, piv, u1);
    for (int i = 0; i < n; i++) xs[i] = x[i] + A21 * u1[i];
    if (call3(kf, c, xs, t + AL2 * h, fs)) return -2;
    for (int i = 0; i < n; i++) u2[i] = fs[i] + C21 / h * u1[i] + h * D2 * ft[i];
    lusolve(n, Wbuf, piv, u2);
    for (int i = 0; i < n; i++) xs[i] = x[i] + A31 * u1[i] + A32 * u2[i];
    if (call3(kf, c, xs, t + AL3 * h, fs)) return -2;
    for (int i = 0; i < n; i++) u3[i] = fs[i] + (C31 * u1[i] + C32 * u2[i]) / h + h * D3 * ft[i];
    lusolve(n, Wbuf, piv, u3);
    for (int i = 0; i < n; i++) {
        x1[i] = x[i] + M1 * u1[i] + M2 * u2[i] + M3 * u3[i];
        errv[i] = E1 * u1[i] + E2 * u2[i] + E3 * u3[i];
    }
    return 0;
}

/*
 * Integrate one mode from (t0, x0) until t_end or the first guard crossing.
 * Samples at k*dt_out > t0 (the global grid) are written to out_t/out_x (row per sample).
 * Returns 0 at t_end, 1 at an event (t_ev, x_ev, j_ev), 2 when the output buffer is full
 * (t_ev, x_ev hold the last accepted integrator point, where the caller restarts), -1 singular
 * matrix, -2 function error, -3 step size underflow, -4 too many steps, -5 too many states,
 * -6 a state beyond +-runaway (j_ev names it), -7 bad arguments, -8 out of memory.
 */
int kiln_run(int n, int ng, const double* P, double t0, double t_end, const double* x0, double dt_out,
             double rtol, double atol, double hmax, double h0, double event_tol, int max_out, double* out_t,
             double* out_x, int* n_out, double* t_ev, double* x_ev, int* j_ev, int max_steps, int* n_steps,
             double* h_last, double runaway, double guard_eps) {
    n_out[0] = 0; n_steps[0] = 0; h_last[0] = 0.0;
    if (n > NMAX || ng > GMAX || n < 1 || ng < 0) return -5;
    if (max_out < 2 || !(dt_out > 0) || !(hmax > 0) || !(h0 > 0)) return -7;
    /* a step never spans more output samples than half the buffer, so a restart always makes progress */
    if (hmax > 0.5 * max_out * dt_out) hmax = 0.5 * max_out * dt_out;
    ctx_t* c = (ctx_t*)malloc(sizeof(ctx_t));
    if (c == NULL) return -8;
    c->P = P;
    double x[NMAX], f0[NMAX], x1[NMAX], f1[NMAX], errv[NMAX], ft[NMAX], tmp[NMAX];
    double J[NMAX * NMAX], W[NMAX * NMAX];
    double g0[GMAX], g1[GMAX], gt[GMAX], gi[GMAX];
    int piv[NMAX];
    int status = 0, steps = 0, nout = 0;
    double t = t0, h = h0;  /* the first step comes from Python (kilnctl.model.stepper.FIRST_STEP); capped below */
    memcpy(x, x0, n * sizeof(double));
    if (call3(kf, c, x, t, f0) || call3(kg, c, x, t, g0)) { status = -2; goto done; }
    /* samples on the global grid k*dt_out, after t0 */
    double k0 = floor(t0 / dt_out * (1 + 1e-14)) + 1.0;
    double t_next_out = k0 * dt_out, t1 = t;
    while (t < t_end) {
        if (steps >= max_steps) { status = -4; break; }
        if (call3(kj, c, x, t, J) || call3(kt, c, x, t, ft)) { status = -2; break; }
        double err;
        for (;;) {
            if (h > hmax) h = hmax;
            int last = 0;
            if (t + h >= t_end) { h = t_end - t; last = 1; }
            if (h < 1e-14 * fmax(1.0, fabs(t))) { status = -3; goto done; }
            int r = ros_step(c, n, t, x, f0, J, ft, h, x1, errv, W, piv);
            if (r == -1) { h *= 0.25; continue; }
            if (r < 0) { status = -2; goto done; }
            err = 0.0;
            for (int i = 0; i < n; i++) {
                double sc = atol + rtol * fmax(fabs(x[i]), fabs(x1[i]));
                double e = errv[i] / sc;
                err += e * e;
            }
            err = sqrt(err / n);
            if (err <= 1.0) {
                /* dense output check: the Hermite cubic's slope at mid-step against f there */
                double tm = t + 0.5 * h, fm[NMAX], dp, ei = 0.0;
                if (call3(kf, c, x1, t + h, f1)) { status = -2; goto done; }
                hermite(n, t, x, f0, t + h, x1, f1, tm, tmp);
                if (call3(kf, c, tmp, tm, fm)) { status = -2; goto done; }
                for (int i = 0; i < n; i++) {
                    dp = 1.5 * (x1[i] - x[i]) / h - 0.25 * (f0[i] + f1[i]);
                    double sc = atol + rtol * fmax(fabs(x[i]), fabs(x1[i]));
                    double e = h * (fm[i] - dp) / (6.0 * sc);
                    ei += e * e;
                }
                ei = sqrt(ei / n);
                if (ei > err) err = ei;
            }
            if (!(err == err)) { h *= 0.25; continue; }  /* NaN */
            double fac = err > 0 ? 0.9 * pow(err, -1.0 / 3.0) : 5.0;
            fac = fmin(5.0, fmax(0.2, fac));
            if (err <= 1.0) {
                t1 = last ? t_end : t + h;
                h *= fac;
                break;
            }
            h *= fmax(0.2, fac);
        }
        steps++;
        if (call3(kg, c, x1, t1, g1)) { status = -2; break; }
        /* Guards are checked at every grid point k*dt_out inside (t, t1), on the step's interpolant, so
           that an excursion longer than dt_out is seen whatever the step size, and at t1.  At the first
           check point where a guard is below -guard_eps, its crossing is located by Illinois on real
           steps from (t, x).  A crossing seen only on the interpolant must be confirmed by a real step;
           a false alarm (interpolant and real step differ by the local error near a tangency, or when
           the crossing lies within the error of a grid point) does NOT end the scan: the later check
           points and t1 are still examined, so a real crossing later in the step is never skipped.
           The CVODES engine locates crossings with its own Illinois iteration in Python
           (kilnctl/simulate.py, _Engine.locate): kept apart on purpose, so the engines check each other. */
        int jbest = -1; double tbest = t1;
        if (ng > 0) {
            double kk = floor(t / dt_out * (1 + 1e-14)) + 1.0;
            for (;;) {
                double tau = kk * dt_out;
                const double* gv;
                int at_end = !(tau < t1 * (1 - 1e-14));
                if (at_end) { tau = t1; gv = g1; }
                else {
                    hermite(n, t, x, f0, t1, x1, f1, tau, tmp);
                    if (call3(kg, c, tmp, tau, gt)) { status = -2; goto done; }
                    memcpy(gi, gt, ng * sizeof(double));
                    gv = gi;
                    kk += 1.0;
                }
                for (int j = 0; j < ng; j++) {
                    if (!(gv[j] < -guard_eps)) continue;
                    double a = t, fa = g0[j] > 0 ? g0[j] : 1e-300, b = tau, fb = gv[j];
                    int side = 0, b_real = at_end;  /* fb from a real step, or from the interpolant */
                    for (int it = 0; it < 100 && b - a > event_tol; it++) {
                        double m = b - fb * (b - a) / (fb - fa);
                        if (!(m > a && m < b)) m = 0.5 * (a + b);
                        if (ros_step(c, n, t, x, f0, J, ft, m - t, tmp, errv, W, piv)) { status = -2; goto done; }
                        if (call3(kg, c, tmp, m, gt)) { status = -2; goto done; }
                        if (gt[j] > 0) { a = m; fa = gt[j]; if (side == -1) fb *= 0.5; side = -1; }
                        else { b = m; fb = gt[j]; b_real = 1; if (side == 1) fa *= 0.5; side = 1; }
                        if (fb == 0.0) break;
                    }
                    if (!b_real) {
                        if (ros_step(c, n, t, x, f0, J, ft, b - t, tmp, errv, W, piv)) { status = -2; goto done; }
                        if (call3(kg, c, tmp, b, gt)) { status = -2; goto done; }
                        if (!(gt[j] < -guard_eps)) continue;  /* false alarm for this guard at this point */
                    }
                    if (jbest < 0 || b < tbest) { tbest = b; jbest = j; }
                }
                if (jbest >= 0 || at_end) break;
            }
        }
        double t_stop = t1;
        if (jbest >= 0) {
            /* the state at the event: a real step from (t, x), on the far side of the guard */
            double he = tbest - t;
            if (he > 0) {
                if (ros_step(c, n, t, x, f0, J, ft, he, tmp, errv, W, piv)) { status = -2; break; }
            } else memcpy(tmp, x, n * sizeof(double));
            t_stop = tbest;
        }
        /* samples on the output grid up to t_stop; when they do not fit in the buffer, stop BEFORE this
           step at the accepted point (t, x) (nothing of this step is written), so a restart continues
           from an integrator state, never from an interpolated sample */
        {
            int need = 0;
            for (double tn = t_next_out; tn <= t_stop * (1 + 1e-15) && tn <= t_end * (1 + 1e-15);
                 tn = (k0 + nout + (++need)) * dt_out) {}
            if (nout + need > max_out) {
                /* the restart repeats this very step (same size from the same point): bit-identical */
                status = 2; t_ev[0] = t; memcpy(x_ev, x, n * sizeof(double)); steps--;
                h = t1 - t;
                break;
            }
        }
        while (t_next_out <= t_stop * (1 + 1e-15) && t_next_out <= t_end * (1 + 1e-15)) {
            out_t[nout] = t_next_out;
            hermite(n, t, x, f0, t1, x1, f1, t_next_out, out_x + (size_t)nout * n);
            nout++;
            t_next_out = (k0 + nout) * dt_out;
        }
        if (jbest >= 0) {
            t_ev[0] = tbest; memcpy(x_ev, tmp, n * sizeof(double)); j_ev[0] = jbest; status = 1; break;
        }
        t = t1;
        memcpy(x, x1, n * sizeof(double)); memcpy(f0, f1, n * sizeof(double)); memcpy(g0, g1, ng * sizeof(double));
        for (int i = 0; i < n; i++) {
            if (!(fabs(x[i]) <= runaway)) {  /* also catches NaN */
                status = (x[i] == x[i]) ? -6 : -2; j_ev[0] = i; t_ev[0] = t; memcpy(x_ev, x, n * sizeof(double));
                break;
            }
        }
        if (status) break;
    }
    if (status == 0) { t_ev[0] = t; memcpy(x_ev, x, n * sizeof(double)); }
done:
    n_out[0] = nout;
    n_steps[0] = steps;
    h_last[0] = h;
    free(c);
    return status;
}

/* Interface version of this driver (see KILN_ABI). */
int kiln_abi(void) { return KILN_ABI; }

/* 0 when the generated functions have the arguments this driver passes (x, t, P; kd with three
   results) and fit the fixed work arrays of ctx_t. */
int kiln_check(void) {
    if (kf_n_in() != 3 || kj_n_in() != 3 || kt_n_in() != 3 || kg_n_in() != 3 || ko_n_in() != 3 ||
        kd_n_in() != 3 || kp_n_in() != 3 || kd_n_out() != 3) return 2;
    int (*works[7])(cint*, cint*, cint*, cint*) = {kf_work, kj_work, kt_work, kg_work, ko_work, kd_work, kp_work};
    for (int k = 0; k < 7; k++) {
        cint a, r, iw, w;
        if (works[k](&a, &r, &iw, &w)) return -1;
        if (a > 64 || r > 64 || iw > 4096 || w > 65536) return 1;
    }
    return 0;
}

/* Outputs y_i = ko(x_i, t_i, P) of k samples; X is k x n and Y is k x ny, row per sample. */
int kiln_outputs(int n, int ny, const double* P, int k, const double* T, const double* X, double* Y) {
    ctx_t* c = (ctx_t*)malloc(sizeof(ctx_t));
    if (c == NULL) return -8;
    c->P = P;
    int status = 0;
    for (int i = 0; i < k; i++)
        if (call3(ko, c, X + (size_t)i * n, T[i], Y + (size_t)i * ny)) { status = -2; break; }
    free(c);
    return status;
}

/* Guards g, selectors and dg/dt at one point (the simulator's mode cascade). */
int kiln_guard(const double* P, const double* x, double t, double* g, double* sel, double* gdot) {
    ctx_t* c = (ctx_t*)malloc(sizeof(ctx_t));
    if (c == NULL) return -8;
    c->P = P;
    c->arg[0] = x; c->arg[1] = &t; c->arg[2] = P;
    c->res[0] = g; c->res[1] = sel; c->res[2] = gdot;
    int st = kd(c->arg, c->res, c->iw, c->w, 0);
    free(c);
    return st;
}

/* State projected onto the mode's constraints: node speeds onto the rigid links (momentum kept), a held
   current onto its limit. */
int kiln_project(const double* P, const double* x, double t, double* out) {
    ctx_t* c = (ctx_t*)malloc(sizeof(ctx_t));
    if (c == NULL) return -8;
    c->arg[0] = x; c->arg[1] = &t; c->arg[2] = P;
    c->res[0] = out;
    int st = kp(c->arg, c->res, c->iw, c->w, 0);
    free(c);
    return st;
}
