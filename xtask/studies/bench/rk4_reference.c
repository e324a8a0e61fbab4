/* A plain hand-written RK4 loop of the Bouc-Wen benchmark oscillator, the reference that
 * `cargo xtask bench rk4` runs beside `hyst_sim::simulate` (same sizes: 2^20 samples at
 * 750 Hz, 20 sub-steps per sample, input linearly interpolated, output sub-sampled).
 * Built by the bench with `cc -O3 -march=native -ffp-contract=fast`. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* m x'' + c x' + k x + z = u,  z' = alpha x' - bg |x'| z - bd x' |z| */
static const double m = 2, c = 10, k = 5e4, alpha = 5e4, bg = 800, bd = -1100;

static void rate(double x, double v, double z, double u, double *dx, double *dv, double *dz) {
    *dx = v;
    *dv = (u - c * v - k * x - z) * (1.0 / m);
    *dz = v * (alpha - bd * fabs(z)) - bg * fabs(v) * z;
}

int main(void) {
    const int n = 1 << 20, r = 20;
    const double h = 1.0 / (750.0 * r);
    double *u = malloc(n * sizeof *u), *y = malloc(n * sizeof *y);
    unsigned s = 1;
    for (int i = 0; i < n; i++) { /* uniform noise, RMS 50 N */
        s = s * 1664525u + 1013904223u;
        u[i] = 50.0 * 3.4641016 * ((s >> 8) / 16777216.0 - 0.5);
    }
    double best = 1e30;
    for (int rep = 0; rep < 3; rep++) {
        double t0 = now(), x = 0, v = 0, z = 0;
        y[0] = 0;
        for (int i = 0; i < n - 1; i++) {
            double du = (u[i + 1] - u[i]) / r;
            for (int j = 0; j < r; j++) {
                double ua = u[i] + du * j, um = ua + 0.5 * du, ub = ua + du;
                double a1, b1, c1, a2, b2, c2, a3, b3, c3, a4, b4, c4;
                rate(x, v, z, ua, &a1, &b1, &c1);
                rate(x + 0.5 * h * a1, v + 0.5 * h * b1, z + 0.5 * h * c1, um, &a2, &b2, &c2);
                rate(x + 0.5 * h * a2, v + 0.5 * h * b2, z + 0.5 * h * c2, um, &a3, &b3, &c3);
                rate(x + h * a3, v + h * b3, z + h * c3, ub, &a4, &b4, &c4);
                x += h / 6 * (a1 + 2 * a2 + 2 * a3 + a4);
                v += h / 6 * (b1 + 2 * b2 + 2 * b3 + b4);
                z += h / 6 * (c1 + 2 * c2 + 2 * c3 + c4);
            }
            y[i + 1] = x;
        }
        double t = now() - t0;
        if (t < best) best = t;
    }
    /* Print a sample of the output so the loop cannot be optimised away. */
    printf("%.3f %g\n", best / ((double)(n - 1) * r) * 1e9, y[n - 1]);
    free(u);
    free(y);
    return 0;
}
