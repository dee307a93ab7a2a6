// Ownership, the halo and the global edge numbering: the collective part of creating a
// distributed scene. Each global id has a home rank (ids split into equal ranges over the
// ranks), which sees every claim on it and so can check it: owned once, copies owned by
// someone, a triangle's copies with its owner's vertices.
#include <algorithm>
#include <array>
#include <tuple>
#include <unordered_map>

#include "collective.h"
#include "scene.h"

namespace minkq::mpi {

namespace {

// The global range [lo, hi] of some ids, split into `size` equal home ranges, in id order.
struct Homes {
  int64_t lo = 0, hi = -1;
  int size = 1;
  int of(int64_t id) const {
    const unsigned __int128 span = (unsigned __int128)(uint64_t(hi - lo)) + 1;
    return int((unsigned __int128)(uint64_t(id - lo)) * (unsigned __int128)size / span);
  }
};

Homes homes_of(MPI_Comm comm, int size, const std::vector<int64_t>& ids) {
  int64_t local[2] = {INT64_MAX, INT64_MIN};  // (min, -max) in one reduction
  for (int64_t id : ids) local[0] = std::min(local[0], id), local[1] = std::max(local[1], id);
  local[1] = local[1] == INT64_MIN ? INT64_MAX : -local[1];
  int64_t global[2];
  mpi_check(MPI_Allreduce(local, global, 2, MPI_INT64_T, MPI_MIN, comm), "MPI_Allreduce");
  Homes h;
  h.size = size;
  if (global[0] != INT64_MAX) h.lo = global[0], h.hi = -global[1];
  return h;
}

struct VertexClaim {
  int64_t id;
  int32_t local;
  int32_t owned;
};
struct OwnerReply {
  int32_t local;
  int32_t owner;
};
struct TriangleClaim {
  int64_t id;
  int64_t v[3];  // global vertex ids, sorted
  int32_t local;
  int32_t owned;
};
struct EdgeClaim {
  int64_t a, b;       // global vertex ids, a <= b
  int64_t triangle;   // the lowest-id owned triangle of the sender that the edge bounds
};
struct EdgeReply {
  int64_t id;
  int64_t owned;
};

// A received record with where it came from.
template <class T>
struct From {
  T record;
  int rank;
  int index;  // its position in that rank's message
};
template <class T>
std::vector<From<T>> tagged(const std::vector<T>& records, const std::vector<int>& counts) {
  std::vector<From<T>> out(records.size());
  size_t k = 0;
  for (int p = 0; p < int(counts.size()); ++p)
    for (int i = 0; i < counts[p]; ++i, ++k) out[k] = {records[k], p, i};
  return out;
}

std::string vertex_at(int rank, int32_t local) {
  return "rank " + std::to_string(rank) + " (its local vertex " + std::to_string(local) + ")";
}
std::string triangle_at(int rank, int32_t local) {
  return "rank " + std::to_string(rank) + " (its local triangle " + std::to_string(local) + ")";
}

}  // namespace

minkq_status setup_ownership(SceneState& s, const std::vector<int32_t>& local_triangles,
                             const std::vector<int64_t>& local_triangle_ids, const std::vector<uint8_t>& triangle_owned) {
  const int size = s.size;
  // ---- Vertices: claims to the homes, checked there; each copy learns its owner.
  const Homes vhomes = homes_of(s.comm, size, s.vertex_ids);
  std::vector<std::vector<VertexClaim>> claims(size);
  std::vector<int> counts;
  std::vector<VertexClaim> received;
  minkq_status status = phase(s.comm, [&] {
    for (size_t i = 0; i < s.vertex_ids.size(); ++i)
      claims[vhomes.of(s.vertex_ids[i])].push_back({s.vertex_ids[i], int32_t(i), int32_t(s.vertex_owned[i])});
  });
  if (status) return status;
  received = alltoallv(s.comm, claims, &counts);
  std::vector<std::vector<OwnerReply>> replies(size);
  status = phase(s.comm, [&] {
    auto all = tagged(received, counts);
    std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) {
      return std::tie(x.record.id, y.record.owned, x.rank) < std::tie(y.record.id, x.record.owned, y.rank);
    });
    for (size_t i = 0; i < all.size();) {
      size_t j = i;
      while (j < all.size() && all[j].record.id == all[i].record.id) ++j;
      const auto& first = all[i];
      if (j - i > 1 && all[i + 1].record.owned)
        fail(MINKQ_ERROR_INVALID_ARGUMENT, "global vertex " + std::to_string(first.record.id) + " is owned by " +
                                               vertex_at(first.rank, first.record.local) + " and by " +
                                               vertex_at(all[i + 1].rank, all[i + 1].record.local));
      if (!first.record.owned)
        fail(MINKQ_ERROR_INVALID_ARGUMENT, "global vertex " + std::to_string(first.record.id) + " has a copy on " +
                                               vertex_at(first.rank, first.record.local) + " but no rank owns it");
      for (size_t k = i + 1; k < j; ++k) replies[all[k].rank].push_back({all[k].record.local, first.rank});
      i = j;
    }
  });
  if (status) return status;
  const std::vector<OwnerReply> owners = alltoallv(s.comm, replies);

  // ---- The halo: each copy asks its owner, which finds the vertex by id.
  std::vector<std::vector<int64_t>> asks(size);
  {
    std::vector<std::vector<int32_t>> fill(size);
    for (const OwnerReply& r : owners) fill[r.owner].push_back(r.local), asks[r.owner].push_back(s.vertex_ids[r.local]);
    for (int p = 0; p < size; ++p)
      if (!fill[p].empty()) s.halo.sources.push_back(p), s.halo.fill.push_back(std::move(fill[p]));
  }
  const std::vector<int64_t> asked = alltoallv(s.comm, asks, &counts);
  status = phase(s.comm, [&] {
    size_t k = 0;
    for (int q = 0; q < size; ++q) {
      if (!counts[q]) continue;
      std::vector<int32_t> send{};
      send.resize(size_t(counts[q]));
      // The rank's index of its own vertices; the home checked that this rank owns each one asked.
      for (int32_t& v : send) v = s.local_index.at(asked[k++]);
      s.halo.dests.push_back(q), s.halo.send.push_back(std::move(send));
    }
  });
  if (status) return status;

  // ---- Triangles: owned once, copies owned by someone and with the owner's vertices.
  const Homes thomes = homes_of(s.comm, size, local_triangle_ids);
  std::vector<std::vector<TriangleClaim>> tclaims(size);
  status = phase(s.comm, [&] {
    for (size_t t = 0; t < local_triangle_ids.size(); ++t) {
      TriangleClaim c{local_triangle_ids[t], {}, int32_t(t), int32_t(triangle_owned[t])};
      for (int k = 0; k < 3; ++k) c.v[k] = s.vertex_ids[size_t(local_triangles[3 * t + k])];
      std::sort(c.v, c.v + 3);
      tclaims[thomes.of(c.id)].push_back(c);
    }
  });
  if (status) return status;
  const std::vector<TriangleClaim> treceived = alltoallv(s.comm, tclaims, &counts);
  status = phase(s.comm, [&] {
    auto all = tagged(treceived, counts);
    std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) {
      return std::tie(x.record.id, y.record.owned, x.rank) < std::tie(y.record.id, x.record.owned, y.rank);
    });
    auto ids = [](const int64_t v[3]) {
      return "(" + std::to_string(v[0]) + ", " + std::to_string(v[1]) + ", " + std::to_string(v[2]) + ")";
    };
    for (size_t i = 0; i < all.size();) {
      size_t j = i;
      while (j < all.size() && all[j].record.id == all[i].record.id) ++j;
      const auto& first = all[i];
      const std::string name = "global triangle " + std::to_string(first.record.id);
      if (j - i > 1 && all[i + 1].record.owned)
        fail(MINKQ_ERROR_INVALID_ARGUMENT, name + " is owned by " + triangle_at(first.rank, first.record.local) +
                                               " and by " + triangle_at(all[i + 1].rank, all[i + 1].record.local));
      if (!first.record.owned)
        fail(MINKQ_ERROR_INVALID_ARGUMENT,
             name + " has a copy on " + triangle_at(first.rank, first.record.local) + " but no rank owns it");
      for (size_t k = i + 1; k < j; ++k)
        if (!std::equal(first.record.v, first.record.v + 3, all[k].record.v))
          fail(MINKQ_ERROR_INVALID_ARGUMENT, name + " has global vertices " + ids(first.record.v) + " on its owner " +
                                                 triangle_at(first.rank, first.record.local) + " but " +
                                                 ids(all[k].record.v) + " on " +
                                                 triangle_at(all[k].rank, all[k].record.local));
      i = j;
    }
    // Keep the owned triangles only.
    s.triangles.clear(), s.triangle_ids.clear();
    for (size_t t = 0; t < local_triangle_ids.size(); ++t)
      if (triangle_owned[t]) {
        s.triangles.insert(s.triangles.end(), local_triangles.begin() + 3 * t, local_triangles.begin() + 3 * t + 3);
        s.triangle_ids.push_back(local_triangle_ids[t]);
      }
  });
  return status;
}

void exchange_halo(SceneState& s) {
  std::vector<std::vector<std::array<float, 3>>> send(s.halo.dests.size());
  for (size_t i = 0; i < send.size(); ++i)
    for (int32_t v : s.halo.send[i]) send[i].push_back({s.xyz[3 * v], s.xyz[3 * v + 1], s.xyz[3 * v + 2]});
  s.bytes_sent += payload(send);
  const auto in = neighbour_exchange(s.comm, s.halo.dests, send, s.halo.sources);
  for (size_t j = 0; j < in.size(); ++j)
    for (size_t k = 0; k < in[j].size(); ++k)
      std::copy(in[j][k].begin(), in[j][k].end(), s.xyz.begin() + 3 * size_t(s.halo.fill[j][k]));
}

minkq_status setup_edges(SceneState& s) {
  const int size = s.size;
  const Homes homes = homes_of(s.comm, size, s.vertex_ids);
  // This rank's distinct edges of its owned triangles, each with its lowest-id triangle.
  struct Local {
    int64_t a, b, triangle;
    int32_t la, lb;
  };
  std::vector<Local> local;
  std::vector<std::vector<EdgeClaim>> claims(size);
  std::vector<std::vector<size_t>> sent(size);  // claims[q][i] is local[sent[q][i]]
  minkq_status status = phase(s.comm, [&] {
    for (size_t t = 0; t < s.triangle_ids.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        int32_t la = s.triangles[3 * t + k], lb = s.triangles[3 * t + (k + 1) % 3];
        if (s.vertex_ids[la] > s.vertex_ids[lb]) std::swap(la, lb);
        local.push_back({s.vertex_ids[la], s.vertex_ids[lb], s.triangle_ids[t], la, lb});
      }
    std::sort(local.begin(), local.end(),
              [](const Local& x, const Local& y) { return std::tie(x.a, x.b, x.triangle) < std::tie(y.a, y.b, y.triangle); });
    local.erase(std::unique(local.begin(), local.end(),
                            [](const Local& x, const Local& y) { return x.a == y.a && x.b == y.b; }),
                local.end());
    for (size_t i = 0; i < local.size(); ++i) {
      const int home = homes.of(local[i].a);
      claims[home].push_back({local[i].a, local[i].b, local[i].triangle});
      sent[home].push_back(i);
    }
  });
  if (status) return status;
  std::vector<int> counts;
  const std::vector<EdgeClaim> received = alltoallv(s.comm, claims, &counts);
  // The home numbers its distinct edges in order; the owner is the sender of the lowest triangle.
  auto all = tagged(received, counts);
  std::sort(all.begin(), all.end(), [](const auto& x, const auto& y) {
    return std::tie(x.record.a, x.record.b, x.record.triangle) < std::tie(y.record.a, y.record.b, y.record.triangle);
  });
  int64_t distinct = 0;
  for (size_t i = 0; i < all.size(); ++i)
    distinct += i == 0 || all[i].record.a != all[i - 1].record.a || all[i].record.b != all[i - 1].record.b;
  int64_t first_id = 0;
  mpi_check(MPI_Exscan(&distinct, &first_id, 1, MPI_INT64_T, MPI_SUM, s.comm), "MPI_Exscan");
  if (s.rank == 0) first_id = 0;
  int64_t total = 0;
  mpi_check(MPI_Allreduce(&distinct, &total, 1, MPI_INT64_T, MPI_SUM, s.comm), "MPI_Allreduce");
  std::vector<std::vector<EdgeReply>> replies(size);
  for (int p = 0; p < size; ++p) replies[p].resize(size_t(counts[p]));
  int64_t id = first_id - 1;
  int owner = -1;
  for (size_t i = 0; i < all.size(); ++i) {
    if (i == 0 || all[i].record.a != all[i - 1].record.a || all[i].record.b != all[i - 1].record.b)
      ++id, owner = all[i].rank;
    replies[all[i].rank][all[i].index] = {id, all[i].rank == owner};
  }
  std::vector<int> reply_counts;
  const std::vector<EdgeReply> answers = alltoallv(s.comm, replies, &reply_counts);
  size_t k = 0;
  s.edges.clear();
  for (int q = 0; q < size; ++q)
    for (size_t i = 0; i < sent[q].size(); ++i, ++k)
      if (answers[k].owned) s.edges.push_back({local[sent[q][i]].la, local[sent[q][i]].lb, answers[k].id});
  s.global_edges = uint64_t(total);
  return MINKQ_SUCCESS;
}

}  // namespace minkq::mpi
