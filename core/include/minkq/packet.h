// Query packets, the host's walk: up to kPacket neighbouring queries of a batch (consecutive in
// the batch's order: Morton-ordered vertices, or a self-query's consecutive leaf positions)
// walk the tree together, each node's child boxes tested against all members' box tests at
// once (one member per float lane: four at SSE2, eight in the backend's AVX2 copy, cpu/isa.h),
// so that a node that several members reach is read and tested once for them. A leaf range
// that several members reach is scanned once for them too (scan_together), and each member's
// hits go through its own bound, finer test and filter, as in its own traversal.
//
// The pairs are exactly those of traverse_groups for each member: a member enters a node when
// its box test passes the node's box and the node holds positions after its bound, which is
// the single walk's rule (its self-query path only skips tests that pass), so each member
// reaches the leaf ranges it would alone, tested the same way. Only their order differs (the
// C API leaves it unspecified). Host code only; CUDA threads walk alone (traversal.h).
#pragma once

#include <utility>

#include "minkq/leaf_filter.h"

#if !defined(__CUDACC__)
namespace minkq {

// Queries per packet: the float lanes of the widest vector the compile has (AVX: 8, else 4).
// The width names the inline namespace, so that code of both widths may meet in one program
// (the baseline core beside a test compiled for AVX2) without their packets sharing a symbol.
#if defined(__AVX__)
inline namespace packets8 {
constexpr int kPacket = 8;
#else
inline namespace packets4 {
constexpr int kPacket = 4;
#endif
namespace packet_lanes {
typedef float F __attribute__((vector_size(4 * kPacket)));
typedef int32_t M __attribute__((vector_size(4 * kPacket)));  // -1 (true) or 0 per lane
#if defined(__AVX__)
inline F splat(float x) { return F{x, x, x, x, x, x, x, x}; }
inline unsigned mask_bits(M m) { return unsigned(__builtin_ia32_movmskps256((F)m)); }  // each lane's sign
#else
inline F splat(float x) { return simd4::splat(x); }
inline unsigned mask_bits(M m) { return simd4::mask_bits(m); }
#endif
// Bit i: bit `bit` of bytes[i], for 32 bytes (one column of a 32 x 8 bit matrix).
inline uint32_t column(const uint8_t (&bytes)[32], unsigned bit) {
  typedef uint8_t B __attribute__((vector_size(16)));
  typedef char C __attribute__((vector_size(16)));
  B lo, hi;
  memcpy(&lo, bytes, 16);
  memcpy(&hi, bytes + 16, 16);
  const B b = B{} + uint8_t(1u << bit);
  return uint32_t(__builtin_ia32_pmovmskb128((C)((lo & b) == b))) |
         uint32_t(__builtin_ia32_pmovmskb128((C)((hi & b) == b))) << 16;
}
}  // namespace packet_lanes

// A packet's box tests, member j in lane j: box_gap_within(lo_j, hi_j, r_j, b) for one box b
// against every member at once, the scalar test's subtractions and comparisons lane by lane
// (b's faces broadcast), so each lane's verdict is the member's own.
struct PacketBoxes {
  packet_lanes::F lo[3], hi[3], r;
  packet_lanes::M after;  // each member's bound (traverse_groups' `after`)

  template <class Shape>
  static PacketBoxes of(const Shape (&shapes)[kPacket], const int32_t (&bounds)[kPacket]) {
    PacketBoxes p;
    for (int j = 0; j < kPacket; ++j) {
      const BoxShape& b = shapes[j].box_test();
      for (int axis = 0; axis < 3; ++axis) {
        p.lo[axis][j] = component(b.lo, axis);
        p.hi[axis][j] = component(b.hi, axis);
      }
      p.r[j] = b.r;
      p.after[j] = bounds[j];
    }
    return p;
  }
  // The members whose box test accepts b, as bits.
  unsigned overlaps(const Box& b) const {
    using packet_lanes::splat;
    const packet_lanes::M pass = (splat(b.lo.x) - hi[0] <= r) & (lo[0] - splat(b.hi.x) <= r) &
                                 (splat(b.lo.y) - hi[1] <= r) & (lo[1] - splat(b.hi.y) <= r) &
                                 (splat(b.lo.z) - hi[2] <= r) & (lo[2] - splat(b.hi.z) <= r);
    return packet_lanes::mask_bits(pass);
  }
  // The members with a leaf position after their bound at or before `last`.
  unsigned reach(int32_t last) const { return packet_lanes::mask_bits(after < last); }
};

// Members sharing a leaf range at least this many scan it together (scan_together); fewer scan
// it one by one, four boxes a test (visit_leaf_range). A box against all members costs what a
// group of four against one member does, so four lanes need all four members to share it.
constexpr int kScanTogether = kPacket == 8 ? 3 : 4;

// The leaf range [first, last] for the members of `members`, read once for all of them: each
// box tested against every member's box test at once (PacketBoxes::overlaps, the group scan's
// float operations lane by lane), then each member's hits handed on a group at a time, past its
// bound, through its finer test (finer_hits): the groups and hits visit_leaf_range gives it.
template <class Shape, class OnHits>
void scan_together(const BoxGroup* leaf_groups, const PacketBoxes& packet, const Shape (&shapes)[kPacket],
                   const int32_t (&bounds)[kPacket], int32_t first, int32_t last, unsigned members,
                   OnHits (&on_hits)[kPacket]) {
  for (int64_t base = int64_t(first) & ~int64_t(3); base <= last; base += 32) {  // 32 positions a pass
    uint8_t verdicts[32] = {};  // members' bits by position base + i
    unsigned any = 0;           // the members with a hit in this pass
    const int64_t end = last < base + 31 ? last : base + 31;
    for (int64_t p = first > base ? first : base; p <= end; ++p) {
      const unsigned bits = packet.overlaps(group_box(leaf_groups[p >> 2], int(p & 3)));
      verdicts[p - base] = uint8_t(bits);
      any |= bits;
    }
    for (unsigned rest = members & any; rest != 0; rest &= rest - 1u) {
      const int j = lowest_bit(rest);
      uint64_t hits = packet_lanes::column(verdicts, unsigned(j));
      // Past the bound only: the positions from bounds[j] + 1 on (a shift of 32 or more leaves none).
      const int64_t from = int64_t(bounds[j]) + 1 - base;
      hits &= ~uint64_t(0) << (from < 0 ? 0 : from > 63 ? 63 : from);
      while (hits != 0) {
        const int g = __builtin_ctzll(hits) >> 2;
        const BoxGroup& group = leaf_groups[(base >> 2) + g];
        const unsigned lanes = finer_hits(shapes[j], group, unsigned(hits >> (4 * g)) & 0xfu);
        hits &= ~(uint64_t(0xf) << (4 * g));
        if (lanes != 0) on_hits[j](base + 4 * g, lanes, group);
      }
    }
  }
}

// traverse_groups for each member j of `live` (bits below kPacket), on_hits[j] taking its
// groups. shapes[j] and bounds[j] (its `after`) are ignored outside `live`.
template <class Shape, class OnHits>
void traverse_packet(const BvhView& bvh, const Shape (&shapes)[kPacket], const int32_t (&bounds)[kPacket],
                     unsigned live, OnHits (&on_hits)[kPacket]) {
  static_assert(ShapeContract<Shape>::value, "the query shape does not fulfil the Shape contract (shapes.h)");
  if (bvh.num_prims <= 0) return;
  const PacketBoxes packet = PacketBoxes::of(shapes, bounds);
  NoWork work;
  // A leaf range [first, last] whose box the members of `members` accept.
  auto on_range = [&](int32_t first, int32_t last, const Box& range_box, unsigned members) {
    if (first < last && popcount(members) >= kScanTogether) {
      scan_together(bvh.leaf_groups, packet, shapes, bounds, first, last, members, on_hits);
      return;
    }
    for (; members != 0; members &= members - 1u) {
      const int j = lowest_bit(members);
      visit_leaf_range(bvh.leaf_groups, shapes[j], first, last, bounds[j], range_box, on_hits[j], work);
    }
  };
  int32_t stack[kTraversalStack];
  unsigned stack_members[kTraversalStack];
  int sp = 0;
  int32_t node = 0;
  unsigned members = live & packet.reach(bvh.num_prims - 1);
  while (members != 0) {
    const BvhNode& n = bvh.nodes[node];
    int32_t next = -1;
    unsigned next_members = 0;
    // The left child ends at split: only members bound before it go there.
    if (unsigned left = members & packet.reach(n.split)) {
      if ((left &= packet.overlaps(n.left_box)) != 0) {
        if (n.left < 0) on_range(~n.left, n.split, n.left_box, left); else next = n.left, next_members = left;
      }
    }
    if (n.right != kNoChild) {
      if (const unsigned right = members & packet.overlaps(n.right_box)) {
        if (n.right < 0) {
          on_range(n.split + 1, ~n.right, n.right_box, right);
        } else if (next < 0) {
          next = n.right, next_members = right;
        } else {
          stack[sp] = n.right;
          stack_members[sp++] = right;
        }
      }
    }
    if (next >= 0) {
      node = next;
      members = next_members;
      continue;
    }
    if (sp == 0) return;
    node = stack[--sp];
    members = stack_members[sp];
  }
}

// run_packet's members (all kPacket lanes: copies of the first past `count`) walking together.
template <class Shape, class Queries, class Emit, size_t... J>
void walk_packet(const BvhView& bvh, const Queries& queries, const QueryTarget (&targets)[kPacket], int count,
                 Emit& emit, std::index_sequence<J...>) {
  NoWork work;
  const Shape shapes[kPacket] = {Shape::from(queries.geometry(targets[J]))...};
  const int32_t bounds[kPacket] = {targets[J].after...};
  using Filter = LeafFilter<Shape, Queries, Emit, NoWork>;
  Filter filters[kPacket] = {Filter{queries, bvh.sorted_prims, targets[J], emit, work}...};
  traverse_packet(bvh, shapes, bounds, (1u << count) - 1u, filters);
}

// Queries first .. first + count - 1 of the batch (count 1 to kPacket) as one packet: each
// member's pairs are run_query's for it, without work counts.
template <class Shape, class Queries, class Emit>
void run_packet(const BvhView& bvh, const Queries& queries, int32_t first, int count, Emit& emit) {
  static_assert(QuerySourceContract<Queries, Shape>::value, "not a query source (query_sources.h)");
  static_assert(EmitContract<Emit>::value, "not an emitter");
  // A tree of one leaf range has no node for the members to share: each walks alone.
  if (bvh.num_prims <= kLeafSize) {
    NoWork work;
    for (int j = 0; j < count; ++j) run_query<Shape>(bvh, queries, first + j, emit, work);
    return;
  }
  QueryTarget targets[kPacket];
  for (int j = 0; j < kPacket; ++j) targets[j] = queries.target(first + (j < count ? j : 0));
  walk_packet<Shape>(bvh, queries, targets, count, emit, std::make_index_sequence<kPacket>());
}

}  // namespace packets4 / packets8
}  // namespace minkq
#endif
