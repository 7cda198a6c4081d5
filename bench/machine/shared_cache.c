/* Do two cores slow each other down on a working set of a given size?
 * Sums n doubles in a scrambled order (index array, 12 bytes per element),
 * 4e8 reads in all, and prints the time. Run it alone, then two copies at
 * once: on a machine whose cores share a cache or memory path the pair takes
 * longer than one copy alone. docs/micro.md (Speed) uses it to explain why two
 * threads of the micro engine gain less than 2x on the project's machine.
 *   cc -O2 bench/machine/shared_cache.c -o /tmp/shared_cache
 *   for n in 100000 1000000 4000000; do /tmp/shared_cache $n; \
 *     (/tmp/shared_cache $n & /tmp/shared_cache $n & wait); done */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

int main(int argc, char** argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: %s ELEMENTS\n", argv[0]);
    return 2;
  }
  const long n = atol(argv[1]);
  if (n < 1) {
    fprintf(stderr, "ELEMENTS must be >= 1\n");
    return 2;
  }
  double* x = malloc((size_t)n * sizeof *x);
  uint32_t* idx = malloc((size_t)n * sizeof *idx);
  if (!x || !idx) return 1;
  for (long i = 0; i < n; ++i) {
    x[i] = (double)i;
    idx[i] = (uint32_t)(((uint64_t)i * 2654435761u) % (uint64_t)n);
  }
  struct timespec a, b;
  clock_gettime(CLOCK_MONOTONIC, &a);
  double s = 0.0;
  const long reps = 400000000L / n;
  for (long r = 0; r < reps; ++r)
    for (long i = 0; i < n; ++i) s += x[idx[i]] * (double)(r + 1);
  clock_gettime(CLOCK_MONOTONIC, &b);
  printf("n = %ld (%.1f MB): %.3f s (checksum %g)\n", n, (double)n * 12.0 / 1e6,
         (double)(b.tv_sec - a.tv_sec) + (double)(b.tv_nsec - a.tv_nsec) * 1e-9, s);
  free(x);
  free(idx);
  return 0;
}
