/* C-side helpers for the C API fuzzer. A C caller may store any int in an enum-typed field or
 * argument (C enums are integers); doing the same from C++ would be undefined behaviour in the
 * harness itself. These functions let the C API fuzzer (fuzz_capi.cpp and its parts, declared in
 * capi_model.h) pass such values exactly as C code does. */
#include "minkq.h"

minkq_buffer shim_buffer(const void* data, size_t byte_stride, size_t count, int memory) {
  minkq_buffer b;
  b.data = data;
  b.byte_stride = byte_stride;
  b.count = count;
  b.memory = memory;
  return b;
}

void shim_query_desc(minkq_query_desc* d, int kind, int mode, uint32_t flags, float radius) {
  d->kind = kind;
  d->mode = mode;
  d->flags = flags;
  d->radius = radius;
}

void shim_bvh_query_desc(minkq_bvh_query_desc* d, int shape, int mode, uint32_t flags, float radius,
                         minkq_buffer first, minkq_buffer second) {
  d->shape = shape;
  d->mode = mode;
  d->flags = flags;
  d->radius = radius;
  d->first = first;
  d->second = second;
}

minkq_status shim_scene_query(minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs, size_t capacity,
                              int out_memory, minkq_query_info* info) {
  return minkq_scene_query(scene, query, out_pairs, capacity, out_memory, info);
}

minkq_status shim_bvh_query(minkq_bvh* bvh, const minkq_bvh_query_desc* query, int32_t* out_pairs, size_t capacity,
                            int out_memory, minkq_query_info* info) {
  return minkq_bvh_query(bvh, query, out_pairs, capacity, out_memory, info);
}

minkq_status shim_scene_query_vt_ee(minkq_scene* scene, const minkq_query_desc* vt_query,
                                    const minkq_query_desc* ee_query, int32_t* vt_pairs, size_t vt_capacity,
                                    int32_t* ee_pairs, size_t ee_capacity, int out_memory, minkq_query_info* vt_info,
                                    minkq_query_info* ee_info) {
  return minkq_scene_query_vt_ee(scene, vt_query, ee_query, vt_pairs, vt_capacity, ee_pairs, ee_capacity, out_memory,
                                 vt_info, ee_info);
}

const char* shim_status_name(int status) { return minkq_status_name(status); }

minkq_status shim_scene_geometry_range(const minkq_scene* scene, uint32_t geometry, int element, size_t* out_first,
                                       size_t* out_count) {
  return minkq_scene_geometry_range(scene, geometry, (minkq_element)element, out_first, out_count);
}
