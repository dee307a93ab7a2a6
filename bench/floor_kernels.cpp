// The floor section of bench/README.md counts instructions of these kernels (never run or built
// by CMake): the node test of two child boxes and the leaf group test at SSE2, AVX2 and AVX-512,
// the same float operations as box_gap_within (b.lo - q.hi <= r and q.lo - b.hi <= r per axis).
// g++ -O3 -c bench/floor_kernels.cpp -o /tmp/fk.o && objdump -d --no-show-raw-insn /tmp/fk.o |
//   awk '/>:$/ {f = $2} /^ +[0-9a-f]+:\t/ && !/\t(ret|nop|xchg|data16|cs nop)/ {n[f]++} END {for (f in n) print n[f], f}'
#include <immintrin.h>
#include <cstdint>
struct Box { float lo[3], hi[3]; };
struct Node { Box left, right; int32_t l, r, parent, split; };  // bvh.h's 64-byte BvhNode
template <int W> struct Group { float lo[3][W], hi[3][W]; };      // hd.h's BoxGroup at W lanes

// SSE2 (x86-64's baseline): each box's lo and hi in one register (the fourth lane ignored).
unsigned node_sse2(const Node& n, __m128 qlo, __m128 qhi, __m128 r) {
  auto pass = [&](const Box& b) {
    const __m128 ok = _mm_and_ps(_mm_cmple_ps(_mm_sub_ps(_mm_loadu_ps(b.lo), qhi), r),
                                 _mm_cmple_ps(_mm_sub_ps(qlo, _mm_loadu_ps(b.hi)), r));
    return unsigned((_mm_movemask_ps(ok) & 7) == 7);
  };
  return pass(n.left) | pass(n.right) << 1;
}
// AVX2: the same, VEX-encoded (three operands: no copies before a subtraction).
__attribute__((target("avx2"))) unsigned node_avx2(const Node& n, __m128 qlo, __m128 qhi, __m128 r) {
  return node_sse2(n, qlo, qhi, r);
}
// AVX-512: both boxes' 12 floats in one register against (q.hi, -q.lo) with the hi lanes negated
// (exact: (-b.hi) - (-q.lo) = q.lo - b.hi).
__attribute__((target("avx512f,avx512dq"))) unsigned node_avx512(const Node& n, __m512 q, __m512 sign, __m512 r) {
  const __mmask16 ok = _mm512_cmp_ps_mask(_mm512_sub_ps(_mm512_xor_ps(_mm512_maskz_loadu_ps(0xfff, &n), sign), q), r,
                                          _CMP_LE_OQ);
  return unsigned((ok & 0x3f) == 0x3f) | unsigned((ok >> 6) == 0x3f) << 1;
}
// The leaf group test at 4 (SSE2), 8 (AVX2) and 16 (AVX-512) lanes: the lanes asked for that pass.
#define GROUP_TEST(V, load, sub, pass, and_, mask)                                                             \
  mask(and_(and_(and_(pass(sub(load(g.lo[0]), q[3]), r), pass(sub(q[0], load(g.hi[0])), r)),                     \
                 and_(pass(sub(load(g.lo[1]), q[4]), r), pass(sub(q[1], load(g.hi[1])), r))),                     \
            and_(pass(sub(load(g.lo[2]), q[5]), r), pass(sub(q[2], load(g.hi[2])), r)))) & lanes
#define LE4(a, b) _mm_cmple_ps(a, b)
#define LE8(a, b) _mm256_cmp_ps(a, b, _CMP_LE_OQ)
#define LE16(a, b) _mm512_cmp_ps_mask(a, b, _CMP_LE_OQ)
#define AND16(a, b) __mmask16((a) & (b))
unsigned group4(const Group<4>& g, const __m128* q, __m128 r, unsigned lanes) {
  return GROUP_TEST(4, _mm_loadu_ps, _mm_sub_ps, LE4, _mm_and_ps, _mm_movemask_ps);
}
__attribute__((target("avx2"))) unsigned group8(const Group<8>& g, const __m256* q, __m256 r, unsigned lanes) {
  return GROUP_TEST(8, _mm256_loadu_ps, _mm256_sub_ps, LE8, _mm256_and_ps, _mm256_movemask_ps);
}
__attribute__((target("avx512f"))) unsigned group16(const Group<16>& g, const __m512* q, __m512 r, unsigned lanes) {
  return GROUP_TEST(16, _mm512_loadu_ps, _mm512_sub_ps, LE16, AND16, unsigned);
}
