/* The distributed queries from C99: a grid sheet split into bands of rows over the MPI ranks.
 *   mpirun -n 2 example_c_distributed
 * Each rank passes its band: the vertex rows its triangles touch (owning all but the top one,
 * which the next rank owns), and its triangles, all owned, with global ids. Rank 0 then
 * checks that the ranks' VT and EE pair counts add up to those of the whole sheet in one
 * process, and exits 1 if they do not. */
#include <stdio.h>
#include <stdlib.h>

#include <mpi.h>

#include "minkq.h"
#include "minkq_mpi.h"

enum { N = 40 }; /* N x N vertices, unit spacing */

static int fail(const char* call, minkq_status status, const char* message) {
  fprintf(stderr, "%s failed: %s: %s\n", call, minkq_status_name(status), message);
  MPI_Abort(MPI_COMM_WORLD, 1);
  return 1;
}

/* The whole sheet's vertex positions and the two triangles of quad (i, j). */
static void position(int64_t v, float* p) {
  p[0] = (float)(v % N), p[1] = (float)(v / N), p[2] = 0.1f * (float)((v % 3) == 0);
}
static void quad(int i, int j, int32_t* tri, int64_t* id) { /* global vertex ids in tri */
  const int32_t a = j * N + i, b = a + 1, c = a + N, d = c + 1;
  tri[0] = a, tri[1] = b, tri[2] = d, tri[3] = a, tri[4] = d, tri[5] = c;
  id[0] = 2 * ((int64_t)j * (N - 1) + i), id[1] = id[0] + 1;
}

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank, size;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  /* This rank's quad rows [r0, r1) and vertex rows [r0, r1]. */
  const int r0 = rank * (N - 1) / size, r1 = (rank + 1) * (N - 1) / size;
  const int rows = r1 > r0 ? r1 - r0 + 1 : 0;
  const size_t nv = (size_t)rows * N, nt = 2 * (size_t)(r1 - r0) * (N - 1);
  float* xyz = malloc(3 * nv * sizeof(float) + 1);
  int64_t* vertex_ids = malloc(nv * sizeof(int64_t) + 1);
  uint8_t* vertex_owned = malloc(nv + 1);
  int32_t* tris = malloc(3 * nt * sizeof(int32_t) + 1);
  int64_t* triangle_ids = malloc(nt * sizeof(int64_t) + 1);
  uint8_t* triangle_owned = malloc(nt + 1);
  for (size_t v = 0; v < nv; ++v) {
    vertex_ids[v] = (int64_t)r0 * N + (int64_t)v;
    position(vertex_ids[v], xyz + 3 * v);
    vertex_owned[v] = (int)(v / N) + r0 < r1 || r1 == N - 1; /* the top row: the next band's */
  }
  size_t t = 0;
  for (int j = r0; j < r1; ++j)
    for (int i = 0; i < N - 1; ++i, t += 2) {
      quad(i, j, tris + 3 * t, triangle_ids + t);
      for (int k = 0; k < 6; ++k) tris[3 * t + k] -= r0 * N; /* global to local vertex ids */
      triangle_owned[t] = triangle_owned[t + 1] = 1;
    }

  minkq_device* device = NULL;
  minkq_status s = minkq_device_create("cpu", &device);
  if (s) return fail("minkq_device_create", s, minkq_last_error_message());
  minkq_mpi_scene_desc desc = {0};
  desc.flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
  desc.vertices = (minkq_buffer){xyz, 0, nv, MINKQ_MEMORY_HOST};
  desc.triangles = (minkq_buffer){tris, 0, nt, MINKQ_MEMORY_HOST};
  desc.vertex_ids = (minkq_buffer){vertex_ids, 0, nv, MINKQ_MEMORY_HOST};
  desc.triangle_ids = (minkq_buffer){triangle_ids, 0, nt, MINKQ_MEMORY_HOST};
  desc.vertex_owned = (minkq_buffer){vertex_owned, 0, nv, MINKQ_MEMORY_HOST};
  desc.triangle_owned = (minkq_buffer){triangle_owned, 0, nt, MINKQ_MEMORY_HOST};
  minkq_mpi_scene* scene = NULL;
  s = minkq_mpi_scene_create(MPI_COMM_WORLD, device, &desc, &scene);
  if (s) return fail("minkq_mpi_scene_create", s, minkq_mpi_last_error_message());
  minkq_mpi_result* result = NULL;
  if ((s = minkq_mpi_result_create(&result))) return fail("minkq_mpi_result_create", s, minkq_mpi_last_error_message());

  const minkq_query_desc queries[2] = {{MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 0, 0.8f},
                                       {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, 0, 0.8f}};
  uint64_t counts[2], totals[2];
  for (int q = 0; q < 2; ++q) {
    if ((s = minkq_mpi_scene_query(scene, &queries[q], result)))
      return fail("minkq_mpi_scene_query", s, minkq_mpi_last_error_message());
    counts[q] = minkq_mpi_result_count(result); /* this rank's pairs: minkq_mpi_result_pairs */
  }
  MPI_Reduce(counts, totals, 2, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
  int code = 0;
  if (rank == 0) { /* the whole sheet in one process */
    float* all = malloc(3 * N * N * sizeof(float));
    int32_t* all_tris = malloc(6 * (N - 1) * (N - 1) * sizeof(int32_t));
    int64_t ids[2];
    for (int64_t v = 0; v < N * N; ++v) position(v, all + 3 * v);
    for (int j = 0; j < N - 1; ++j)
      for (int i = 0; i < N - 1; ++i) quad(i, j, all_tris + 6 * (j * (N - 1) + i), ids);
    minkq_scene_desc whole = {0};
    whole.flags = desc.flags;
    whole.vertices = (minkq_buffer){all, 0, N * N, MINKQ_MEMORY_HOST};
    whole.triangles = (minkq_buffer){all_tris, 0, 2 * (N - 1) * (N - 1), MINKQ_MEMORY_HOST};
    minkq_scene* one = NULL;
    if ((s = minkq_scene_create(device, &whole, &one))) return fail("minkq_scene_create", s, minkq_last_error_message());
    for (int q = 0; q < 2; ++q) {
      minkq_query_desc d = queries[q];
      d.flags |= MINKQ_QUERY_COUNT;
      minkq_query_info info;
      if ((s = minkq_scene_query(one, &d, NULL, 0, MINKQ_MEMORY_HOST, &info)))
        return fail("minkq_scene_query", s, minkq_last_error_message());
      printf("%s: %llu pairs over %d ranks, %llu in one process\n", q ? "EE" : "VT", (unsigned long long)totals[q],
             size, (unsigned long long)info.count);
      code |= totals[q] != info.count;
    }
    minkq_scene_release(one);
    free(all), free(all_tris);
  }
  MPI_Bcast(&code, 1, MPI_INT, 0, MPI_COMM_WORLD);
  minkq_mpi_result_release(result);
  minkq_mpi_scene_release(scene);
  minkq_device_release(device);
  free(xyz), free(vertex_ids), free(vertex_owned), free(tris), free(triangle_ids), free(triangle_owned);
  MPI_Finalize();
  return code;
}
