// The CPU backend's instruction-set levels: the query loop is compiled once per level
// (cpu/passes.h) and the level is chosen once, at the first query, from what the processor and
// the operating system support, or from MINKQ_CPU_ISA. Every level gives the same pairs in the
// same order: the levels differ only in how many leaf boxes one vector instruction tests.
#pragma once

#include <string>

// The target attributes of the levels' code (cpu/passes.h), as isa.cpp probes them.
#define MINKQ_TARGET_AVX2 "avx2,bmi,bmi2,popcnt,lzcnt,fma"
#define MINKQ_TARGET_AVX512 MINKQ_TARGET_AVX2 ",avx512f,avx512vl,avx512bw,avx512dq,avx512cd"

namespace minkq::cpu {

enum class Isa : int {
  kSse2 = 0,    // x86-64's baseline (and every other processor: no wide level there)
  kAvx2 = 1,    // AVX2 with BMI1/2, POPCNT, LZCNT and FMA (x86-64-v3), the OS saving the ymm state
  kAvx512 = 2,  // AVX-512 F, VL, BW, DQ and CD on top (x86-64-v4), the OS saving the zmm state
};

// "sse2", "avx2", "avx512": the names MINKQ_CPU_ISA takes and the backend's name reports.
const char* isa_name(Isa isa);

// The widest level this processor and its operating system support (CPUID and XGETBV).
Isa detected_isa();

// The level the queries run at: MINKQ_CPU_ISA's when set (one of isa_name's words, at most the
// detected level), else the detected one. Read once; a bad value throws minkq's error
// (kInvalidArgument, naming the variable and the levels this machine has).
Isa active_isa();

// For tests that compare the levels in one process: from now on, queries run at `isa` (at most
// the detected level, else kInvalidArgument). Not thread-safe against running queries.
void set_active_isa(Isa isa);

}  // namespace minkq::cpu
