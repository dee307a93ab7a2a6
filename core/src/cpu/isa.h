// The CPU backend's instruction-set levels. The backend (cpu/backend.cpp) is compiled once for
// x86-64's baseline (SSE2) and, where the build can (core/CMakeLists.txt, MINKQ_CPU_LEVELS), once
// more per wider level, each copy with its own name for its entry point and nothing else shared;
// each CPU device (make_cpu_backend, isa.cpp) gets the widest level this processor, its
// operating system and this build support, or MINKQ_CPU_ISA's. The copies are one source compiled with other flags (no
// FMA contraction, the same float operations), so every level gives the same pairs in the same
// order.
#pragma once

#include <memory>

namespace minkq {
class Backend;
namespace cpu {

enum class Isa : int {
  kSse2 = 0,  // x86-64's baseline (and every other processor's only level)
  kAvx2 = 1,  // x86-64-v3: AVX2, FMA, BMI1/2, LZCNT, MOVBE, F16C; the OS saving the ymm state
  kAvx512 = 2,  // x86-64-v4: AVX-512 F, BW, CD, DQ, VL on top; the OS saving the zmm state
};

// The level this copy of the backend is compiled for.
constexpr Isa kCompiledIsa =
#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512BW__) && defined(__AVX512DQ__)
    Isa::kAvx512;
#elif defined(__AVX2__)
    Isa::kAvx2;
#else
    Isa::kSse2;
#endif

// "sse2", "avx2", "avx512": the words MINKQ_CPU_ISA takes and the device's name reports.
const char* isa_name(Isa isa);

// The widest level that this processor and its operating system (CPUID, XGETBV) and this build
// support.
Isa detected_isa();

// The level CPU devices run at: MINKQ_CPU_ISA's when set (one of isa_name's words, at most the
// detected level), else the detected one. Read at each CPU device's creation; a bad value fails
// it (kInvalidArgument, naming the variable and the levels this machine has).
Isa requested_isa();

// The baseline copy's backend (cpu/backend.cpp).
std::unique_ptr<Backend> make_baseline_backend();

}  // namespace cpu
}  // namespace minkq
