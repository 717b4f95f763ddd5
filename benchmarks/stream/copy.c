/* STREAM's copy kernel (McCalpin), the reference `make roofline` compares hgym's copy loop with:
 * c[j] = a[j] over arrays far beyond the caches, float (the LBM kernel's storage), OpenMP with a
 * static schedule and first-touch initialisation, best of REPS, bytes counted as read + write.
 * Build: gcc -O3 -march=native -fopenmp copy.c -o copy.  Usage: copy [values] [reps].
 * Prints one JSON line: {"threads": n, "copy_gbs": x}. */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv) {
    long n = argc > 1 ? atol(argv[1]) : (1L << 26);
    int reps = argc > 2 ? atoi(argv[2]) : 10;
    float *a = malloc(n * sizeof(float)), *c = malloc(n * sizeof(float));
    if (!a || !c) return 1;
#pragma omp parallel for schedule(static)
    for (long j = 0; j < n; j++) { a[j] = (float)j; c[j] = 0.0f; }
    double best = 1e30;
    for (int r = 0; r < reps; r++) {
        double t = omp_get_wtime();
#pragma omp parallel for schedule(static)
        for (long j = 0; j < n; j++) c[j] = a[j];
        t = omp_get_wtime() - t;
        if (t < best) best = t;
    }
    if (c[n / 2] != a[n / 2]) return 2;
    printf("{\"threads\": %d, \"copy_gbs\": %.3f}\n", omp_get_max_threads(), 2.0 * n * sizeof(float) / best / 1e9);
    return 0;
}
