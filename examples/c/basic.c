/* basic.c: the minkq C API end to end. Two parallel unit triangles 0.01 apart; vertex-triangle
 * and edge-edge queries with radius 0.02 into a caller buffer that is first too small (the
 * library says so and reports the exact count), then big enough; a refit after moving one
 * triangle away; everything released. Every status is checked. */
#include <minkq.h>
#include <stdio.h>
#include <stdlib.h>

/* On failure: print the call, the status and the library's message, then clean up. */
#define CHECK(call)                                                                          \
  do {                                                                                       \
    minkq_status status_ = (call);                                                           \
    if (status_ != MINKQ_SUCCESS) {                                                          \
      fprintf(stderr, "%s failed: %s: %s\n", #call, minkq_status_name(status_),            \
              minkq_last_error_message());                                                   \
      goto fail;                                                                             \
    }                                                                                        \
  } while (0)

static void print_pairs(const char* what, const int32_t* pairs, uint64_t count) {
  uint64_t i;
  printf("%s: %llu pairs:", what, (unsigned long long)count);
  for (i = 0; i < count; ++i) printf(" (%d, %d)", (int)pairs[2 * i], (int)pairs[2 * i + 1]);
  printf("\n");
}

/* Runs a query into a caller buffer: first with room for 2 pairs, then with exactly as many as
 * the library asked for. Returns the pair count, or -1 on failure. */
static long run_query(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, float radius, const char* what) {
  minkq_query_desc q;
  minkq_query_info info;
  int32_t small[2 * 2];
  int32_t* pairs = NULL;
  minkq_status status;
  long count = -1;

  q.kind = kind;
  q.mode = mode;
  q.flags = MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL;
  q.radius = radius;

  status = minkq_scene_query(scene, &q, small, 2, MINKQ_MEMORY_HOST, &info);
  if (status == MINKQ_ERROR_CAPACITY) {
    printf("%s: a buffer of 2 pairs is too small (%s: %s); %llu pairs needed\n", what, minkq_status_name(status),
           minkq_last_error_message(), (unsigned long long)info.count);
    pairs = (int32_t*)malloc(2 * sizeof(int32_t) * (size_t)(info.count ? info.count : 1));
    if (!pairs) {
      fprintf(stderr, "out of memory\n");
      return -1;
    }
    CHECK(minkq_scene_query(scene, &q, pairs, (size_t)info.count, MINKQ_MEMORY_HOST, &info));
    print_pairs(what, pairs, info.count);
  } else {
    CHECK(status);
    print_pairs(what, small, info.count);
  }
  count = (long)info.count;
fail:
  free(pairs);
  return count;
}

int main(void) {
  /* Triangle 0: vertices 0-2 at z = 0; triangle 1: vertices 3-5, the same shape at z = 0.01. */
  float vertices[6 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.01f, 1, 0, 0.01f, 0, 1, 0.01f};
  const int32_t triangles[2 * 3] = {0, 1, 2, 3, 4, 5};
  const float radius = 0.02f;
  minkq_device* device = NULL;
  minkq_scene* scene = NULL;
  minkq_scene_desc desc;
  minkq_buffer moved;
  long vt, ee;
  int i, ok = 0;

  printf("minkq %u.%u.%u (ABI %u)\n", minkq_version() / 10000, minkq_version() / 100 % 100, minkq_version() % 100,
         minkq_abi_version());
  CHECK(minkq_device_create("auto", &device));
  printf("device: %s\n", minkq_device_name(device));

  desc.flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
  desc.vertices.data = vertices;
  desc.vertices.byte_stride = 3 * sizeof(float);
  desc.vertices.count = 6;
  desc.vertices.memory = MINKQ_MEMORY_HOST;
  desc.triangles.data = triangles;
  desc.triangles.byte_stride = 3 * sizeof(int32_t);
  desc.triangles.count = 2;
  desc.triangles.memory = MINKQ_MEMORY_HOST;
  desc.edges.data = NULL; /* count 0: derived from the triangles */
  desc.edges.byte_stride = 0;
  desc.edges.count = 0;
  desc.edges.memory = MINKQ_MEMORY_HOST;
  CHECK(minkq_scene_create(device, &desc, &scene));
  printf("scene: %zu vertices, %zu triangles, %zu edges\n", minkq_scene_vertex_count(scene),
         minkq_scene_triangle_count(scene), minkq_scene_edge_count(scene));

  /* Each vertex lies 0.01 from the other triangle: 6 VT pairs. Every edge of one triangle comes
   * within 0.01 of every edge of the other (they meet in projection): 9 EE pairs. */
  vt = run_query(scene, MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, radius, "VT");
  ee = run_query(scene, MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, radius, "EE");
  if (vt != 6 || ee != 9) {
    fprintf(stderr, "expected 6 VT and 9 EE pairs, got %ld and %ld\n", vt, ee);
    goto fail;
  }

  /* Lift the second triangle by 1: the trees are refitted in place and nothing is near. */
  for (i = 3; i < 6; ++i) vertices[3 * i + 2] += 1.0f;
  moved = desc.vertices;
  CHECK(minkq_scene_refit(scene, moved));
  printf("refit: triangle 1 lifted to z = 1.01\n");
  vt = run_query(scene, MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, radius, "VT");
  ee = run_query(scene, MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, radius, "EE");
  if (vt != 0 || ee != 0) {
    fprintf(stderr, "expected no pairs after the refit, got %ld VT and %ld EE\n", vt, ee);
    goto fail;
  }
  ok = 1;
fail:
  minkq_scene_release(scene);
  minkq_device_release(device);
  printf("%s\n", ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
