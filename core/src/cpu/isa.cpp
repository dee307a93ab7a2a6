// The CPU backend's level (isa.h): what CPUID says the processor has, what XGETBV says the
// operating system saves on a context switch, which levels this build compiled, and
// MINKQ_CPU_ISA's choice among them.
#include "cpu/isa.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <string>

#include "backend.h"

#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>
#endif

// The wider copies of the backend (core/CMakeLists.txt): each one's only global symbol.
#if defined(MINKQ_CPU_LEVEL_AVX2)
extern "C" minkq::Backend* minkqcore_cpu_backend_avx2();
#endif
#if defined(MINKQ_CPU_LEVEL_AVX512)
extern "C" minkq::Backend* minkqcore_cpu_backend_avx512();
#endif

namespace minkq {
namespace cpu {
namespace {

#if defined(__x86_64__) || defined(__i386__)
unsigned long long xcr0() {
  unsigned eax = 0, edx = 0;
  __asm__ volatile("xgetbv" : "=a"(eax), "=d"(edx) : "c"(0));
  return (static_cast<unsigned long long>(edx) << 32) | eax;
}

// x86-64-v3 and v4 as GCC's -march names them, and the OS's saved state for each.
Isa probe() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (!__get_cpuid(1, &a, &b, &c, &d)) return Isa::kSse2;
  const bool avx = (c & bit_AVX) && (c & bit_OSXSAVE), fma = c & bit_FMA, popcnt = c & bit_POPCNT,
             movbe = c & bit_MOVBE, f16c = c & bit_F16C;
  if (!avx || (xcr0() & 0x6) != 0x6) return Isa::kSse2;  // the OS saves xmm and ymm
  unsigned a1 = 0, b1 = 0, c1 = 0, d1 = 0;
  const bool lzcnt = __get_cpuid(0x80000001, &a1, &b1, &c1, &d1) && (c1 & bit_LZCNT);
  if (!__get_cpuid_count(7, 0, &a, &b, &c, &d)) return Isa::kSse2;
  if (!((b & bit_AVX2) && (b & bit_BMI) && (b & bit_BMI2) && fma && popcnt && lzcnt && movbe && f16c)) return Isa::kSse2;
  const unsigned avx512 = bit_AVX512F | bit_AVX512VL | bit_AVX512BW | bit_AVX512DQ | bit_AVX512CD;
  if ((b & avx512) != avx512 || (xcr0() & 0xe0) != 0xe0) return Isa::kAvx2;  // opmask, zmm halves
  return Isa::kAvx512;
}
#else
Isa probe() { return Isa::kSse2; }
#endif

// The widest level this build compiled.
constexpr Isa kBuilt =
#if defined(MINKQ_CPU_LEVEL_AVX512)
    Isa::kAvx512;
#elif defined(MINKQ_CPU_LEVEL_AVX2)
    Isa::kAvx2;
#else
    Isa::kSse2;
#endif

std::string levels_up_to(Isa top) {
  std::string words;
  for (int k = 0; k <= int(top); ++k) words += std::string(k ? ", " : "") + isa_name(Isa(k));
  return words;
}

}  // namespace

const char* isa_name(Isa isa) {
  switch (isa) {
    case Isa::kAvx2: return "avx2";
    case Isa::kAvx512: return "avx512";
    default: return "sse2";
  }
}

Isa detected_isa() {
  static const Isa detected = Isa(std::min(int(probe()), int(kBuilt)));
  return detected;
}

Isa requested_isa() {
  const char* value = std::getenv("MINKQ_CPU_ISA");
  const Isa top = detected_isa();
  if (value == nullptr || *value == '\0') return top;
  for (int k = 0; k <= int(Isa::kAvx512); ++k) {
    if (std::strcmp(value, isa_name(Isa(k))) != 0) continue;
    if (k > int(top))
      fail(Status::kInvalidArgument, std::string("MINKQ_CPU_ISA=") + value + ": this processor and build support " +
                                         levels_up_to(top));
    return Isa(k);
  }
  fail(Status::kInvalidArgument, std::string("MINKQ_CPU_ISA=") + value + ": expected one of sse2, avx2, avx512 " +
                                     "(this processor and build support " + levels_up_to(top) + ")");
}

}  // namespace cpu

// The level requested_isa() chose (never above the detected one).
std::unique_ptr<Backend> make_cpu_backend() {
  [[maybe_unused]] const cpu::Isa isa = cpu::requested_isa();  // unused in a baseline-only build
#if defined(MINKQ_CPU_LEVEL_AVX512)
  if (isa == cpu::Isa::kAvx512) return std::unique_ptr<Backend>(minkqcore_cpu_backend_avx512());
#endif
#if defined(MINKQ_CPU_LEVEL_AVX2)
  if (isa == cpu::Isa::kAvx2) return std::unique_ptr<Backend>(minkqcore_cpu_backend_avx2());
#endif
  return cpu::make_baseline_backend();
}

}  // namespace minkq
