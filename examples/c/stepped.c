/* stepped.c: the stream-ordered calls as a simulator's step uses them. A 32 x 32 sheet folded
 * over itself; each step moves the vertices, refits and runs the VT and EE queries into fixed
 * buffers with minkq_scene_refit_async / minkq_scene_query_vt_ee_async, and between steps grows
 * a buffer whose exact count exceeded it (on CUDA these calls would be recorded into a graph:
 * they neither wait nor allocate; here, on the CPU, they run at once under the same rules). One
 * step feeds a NaN: the call still succeeds, the scene keeps its positions, and
 * minkq_scene_async_status reports the vertex afterwards. Every status is checked. */
#include <math.h>
#include <minkq.h>
#include <stdio.h>
#include <stdlib.h>

#define CHECK(call)                                                                          \
  do {                                                                                       \
    minkq_status status_ = (call);                                                           \
    if (status_ != MINKQ_SUCCESS) {                                                          \
      fprintf(stderr, "%s failed: %s: %s\n", #call, minkq_status_name(status_),            \
              minkq_last_error_message());                                                   \
      goto fail;                                                                             \
    }                                                                                        \
  } while (0)

#define N 32                 /* vertices per side */
#define VERTICES (N * N)
#define TRIANGLES (2 * (N - 1) * (N - 1))

/* The sheet at time t: folded about x = 1/2 into two layers `gap` apart, which close in. */
static void place(float* xyz, double t) {
  int i, j;
  const double gap = 0.04 * (1.0 - 0.2 * t);
  for (j = 0; j < N; ++j)
    for (i = 0; i < N; ++i) {
      const double u = (double)i / (N - 1), v = (double)j / (N - 1);
      float* p = xyz + 3 * (j * N + i);
      p[0] = (float)(u < 0.5 ? u : 1.0 - u);
      p[1] = (float)v;
      p[2] = (float)(u < 0.5 ? 0.0 : gap) + (float)(0.002 * sin(7.0 * v + t));
    }
}

int main(void) {
  float* xyz = malloc(sizeof(float) * 3 * VERTICES);
  int32_t* tris = malloc(sizeof(int32_t) * 3 * TRIANGLES);
  size_t capacity[2] = {16, 16}; /* VT, EE pairs: deliberately small, grown between steps */
  int32_t* pairs[2] = {NULL, NULL};
  uint64_t count[2] = {0, 0};
  minkq_device* dev = NULL;
  minkq_scene* scene = NULL;
  minkq_scene_desc desc = {0};
  minkq_query_desc vt = {MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, 0.02f};
  minkq_query_desc ee = {MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, 0.02f};
  minkq_status status;
  int i, j, k, step, result = EXIT_FAILURE;

  if (!xyz || !tris) goto fail;
  for (k = 0, j = 0; j < N - 1; ++j)
    for (i = 0; i < N - 1; ++i) {
      const int32_t a = j * N + i, b = a + 1, c = a + N, d = c + 1;
      tris[k++] = a, tris[k++] = b, tris[k++] = d;
      tris[k++] = a, tris[k++] = d, tris[k++] = c;
    }
  place(xyz, 0.0);
  for (k = 0; k < 2; ++k)
    if (!(pairs[k] = malloc(sizeof(int32_t) * 2 * capacity[k]))) goto fail;

  CHECK(minkq_device_create("cpu", &dev));
  desc.flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
  desc.vertices = (minkq_buffer){xyz, 0, VERTICES, MINKQ_MEMORY_HOST};
  desc.triangles = (minkq_buffer){tris, 0, TRIANGLES, MINKQ_MEMORY_HOST};
  CHECK(minkq_scene_create(dev, &desc, &scene));
  CHECK(minkq_scene_reserve(scene, MINKQ_RESERVE_REFIT, 0)); /* once, before the loop */

  for (step = 1; step <= 4; ++step) {
    const minkq_buffer vertices = {xyz, 0, VERTICES, MINKQ_MEMORY_HOST};
    place(xyz, (double)step);
    if (step == 3) xyz[3 * 100 + 1] = NAN; /* a bad step: reported later, positions kept */
    CHECK(minkq_scene_refit_async(scene, vertices, NULL));
    CHECK(minkq_scene_query_vt_ee_async(scene, &vt, &ee, pairs[0], capacity[0], &count[0], pairs[1], capacity[1],
                                        &count[1], NULL));
    /* (A CUDA program would wait for its stream here, or read the counts in a later step.) */
    printf("step %d: %llu VT and %llu EE pairs (buffers of %zu and %zu)\n", step, (unsigned long long)count[0],
           (unsigned long long)count[1], capacity[0], capacity[1]);
    for (k = 0; k < 2; ++k)
      if (count[k] > capacity[k]) { /* grow between steps: this step's pairs did not all fit */
        int32_t* grown = realloc(pairs[k], sizeof(int32_t) * 2 * (size_t)(count[k] + count[k] / 8));
        if (!grown) goto fail;
        pairs[k] = grown;
        capacity[k] = (size_t)(count[k] + count[k] / 8);
      }
  }
  status = minkq_scene_async_status(scene, NULL);
  printf("async status: %s: %s\n", minkq_status_name(status), minkq_last_error_message());
  if (status != MINKQ_ERROR_NON_FINITE) goto fail; /* step 3's NaN must have been reported */
  CHECK(minkq_scene_async_status(scene, NULL));     /* and only once */
  result = EXIT_SUCCESS;

fail:
  minkq_scene_release(scene);
  minkq_device_release(dev);
  free(pairs[0]);
  free(pairs[1]);
  free(xyz);
  free(tris);
  return result;
}
