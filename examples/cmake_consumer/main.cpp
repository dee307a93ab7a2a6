// The installed C++ wrapper (minkq.hpp) from a consumer project: the header, the library and the
// CMake package agree on the version, the ABI and the CUDA backend, and a query counts its pairs.
#include <minkq.hpp>

#include <cstdio>
#include <exception>

int main() {
  try {
    const unsigned version = MINKQ_VERSION_MAJOR * 10000 + MINKQ_VERSION_MINOR * 100 + MINKQ_VERSION_PATCH;
    if (minkq_version() != version || minkq_abi_version() != MINKQ_ABI_VERSION ||
        MINKQ_ABI_VERSION != CONSUMER_ABI_VERSION) {
      std::fprintf(stderr, "library %u ABI %u, header %u ABI %u, CMake package ABI %u\n", minkq_version(),
                   minkq_abi_version(), version, MINKQ_ABI_VERSION, CONSUMER_ABI_VERSION);
      return 1;
    }
    if (!CONSUMER_HAS_CUDA) {  // a library without CUDA refuses a CUDA device
      minkq_device* cuda = nullptr;
      minkq_status status = minkq_device_create("cuda", &cuda);
      minkq_device_release(cuda);
      if (status != MINKQ_ERROR_UNSUPPORTED) {
        std::fprintf(stderr, "MINKQ_HAS_CUDA is off but cuda gave %s\n", minkq_status_name(status));
        return 1;
      }
    }
    // Two parallel unit triangles 0.01 apart: each vertex is within 0.02 of the other triangle.
    const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.01f, 1, 0, 0.01f, 0, 1, 0.01f};
    const int32_t tris[] = {0, 1, 2, 3, 4, 5};
    minkq::cxx::Device device = minkq::cxx::open_device("cpu");
    minkq::cxx::Scene scene = minkq::cxx::new_mesh_scene(device.get(), xyz, 6, tris, 2);
    minkq_query_desc query{};
    query.kind = MINKQ_QUERY_VT;
    query.mode = MINKQ_MODE_SPHERE;
    query.flags = MINKQ_QUERY_LEAF_EXACT;
    query.radius = 0.02f;
    int32_t pairs[2 * 16];
    minkq_query_info info{};
    minkq::cxx::check(minkq_scene_query(scene.get(), &query, pairs, 16, MINKQ_MEMORY_HOST, &info), "minkq_scene_query");
    if (info.count != 6) {
      std::fprintf(stderr, "expected 6 VT pairs, got %llu\n", static_cast<unsigned long long>(info.count));
      return 1;
    }
    std::printf("minkq %u ABI %u, CUDA backend %s: 6 VT pairs, ok\n", minkq_version(), minkq_abi_version(),
                CONSUMER_HAS_CUDA ? "on" : "off");
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
