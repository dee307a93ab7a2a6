// The installed C++ wrapper (minkq.hpp) from a consumer project: the header, the library and the
// CMake package agree on the version, the ABI and the CUDA backend, and a query through the C++
// classes (minkq::api) returns the expected pairs and throws on bad input.
#include <minkq.hpp>

#include <cstdio>
#include <exception>
#include <vector>

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
    // The C++ classes (minkq::api): the pairs come back as a std::vector.
    const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.01f, 1, 0, 0.01f, 0, 1, 0.01f};
    const int32_t tris[] = {0, 1, 2, 3, 4, 5};
    const minkq::api::Device device("cpu");
    minkq::api::Scene scene(device, xyz, tris);
    const std::vector<minkq::api::Pair> pairs =
        scene.query({MINKQ_QUERY_VT, 0.02f, MINKQ_MODE_SPHERE, MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL});
    // Each vertex of one triangle against the other: (0, 1), (1, 1), (2, 1), (3, 0), (4, 0), (5, 0).
    const std::vector<minkq::api::Pair> expected{{0, 1}, {1, 1}, {2, 1}, {3, 0}, {4, 0}, {5, 0}};
    if (pairs != expected) {
      std::fprintf(stderr, "expected 6 VT pairs (vertex, other triangle), got %zu\n", pairs.size());
      return 1;
    }
    // A failure throws minkq::api::Error with the status and the library's message.
    try {
      scene.query({MINKQ_QUERY_VT, -1.0f});
      std::fprintf(stderr, "a negative radius was accepted\n");
      return 1;
    } catch (const minkq::api::Error& e) {
      if (e.status() != MINKQ_ERROR_INVALID_ARGUMENT) {
        std::fprintf(stderr, "a negative radius gave %s\n", e.what());
        return 1;
      }
    }
    std::printf("minkq %u ABI %u, CUDA backend %s: 6 VT pairs, ok\n", minkq_version(), minkq_abi_version(),
                CONSUMER_HAS_CUDA ? "on" : "off");
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
