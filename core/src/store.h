// The scene stores, written once for both backends: a mesh store (vertices, topology, the
// triangle and edge trees, VT and EE queries) and a box store (user boxes, their tree, user
// queries). What differs between the CPU and CUDA backends is supplied by an executor, X, whose
// contract executor.h states and checks. cpu/backend.cpp and cuda/backend.cu define the two
// executors; a query's pairs, counts and work counters are the same on both.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#include "backend.h"
#include "executor.h"
#include "geometry.h"
#include "jobs.h"

namespace minkq {

// Calls fn with a default-constructed value of the shape type that `mode` selects, for point
// queries (VT, user spheres: kPoints) or segment and box queries; only the shapes a kind can
// use are compiled for it. Points are zero-length capsules: capsule_ray tests the box, and
// capsule_exact the sphere. The front end rejects sphere mode for segments and any non-box mode
// for box queries before calling.
template <bool kPoints, class Fn>
void with_shape(Mode mode, Fn&& fn) {
  switch (mode) {
    case Mode::kBox: return fn(BoxShape{});
    case Mode::kSphere:
      if constexpr (kPoints) return fn(SphereShape{});
      break;
    case Mode::kCapsuleRay:
      if constexpr (kPoints) return fn(BoxShape{}); else return fn(CapsuleRayShape{});
    case Mode::kCapsuleExact:
      if constexpr (kPoints) return fn(SphereShape{}); else return fn(CapsuleExactShape{});
  }
  fail(Status::kInternal, "mode not available for these queries");
}

// Calls fn with the QueryPass of a request (its shape chosen by with_shape).
template <bool kPoints, class Queries, class Fn>
void with_pass(const QueryRequest& request, const BvhView& bvh, const Queries& queries, int32_t num_queries,
               const PairOutput& out, Fn&& fn) {
  with_shape<kPoints>(request.mode, [&](auto shape) {
    fn(QueryPass<decltype(shape), Queries>{request.kind, bvh, queries, num_queries, out});
  });
}

// Runs the passes of one call on executor x with the work type they need: the counted
// traversal if any pass counts (the others' counts are then dropped), else the uncounted one.
template <class X, class... Pass>
std::array<uint64_t, sizeof...(Pass)> run_counted(X& x, const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                  const Pass&... passes) {
  for (WorkCounts* w : works)
    if (w) return x.template run_passes<WorkCounts>(works, passes...);
  return x.template run_passes<NoWork>(works, passes...);
}

template <class X>
class MeshStoreOn final : public MeshStore {
  static_assert(ExecutorContract<X>::value, "a store runs on an executor (executor.h)");
  template <class T>
  using Array = typename X::template Array<T>;
  using Geometry = GeometryOn<X>;
  using VtJob = VertexTriangleJob;
  using EvJob = VertexEdgeJob;
  using EeJob = EdgeEdgeJob;
  using VvJob = VertexVertexJob;

 public:
  MeshStoreOn(typename X::Device device, std::vector<GeometryInput> inputs) : x_(device) {
    x_.hold();
    FirstIds next;
    for (const GeometryInput& in : inputs) {
      const GeometryShape shape{in.role, int32_t(in.vertices.count), int32_t(in.triangles.size()),
                                int32_t(in.edges.size())};
      shapes_.push_back(shape);
      first_.push_back(next);
      next = {next.vertices + shape.vertices, next.triangles + shape.triangles, next.edges + shape.edges};
    }
    totals_ = next;
    for (const QueryKind kind : {QueryKind::kVertexTriangle, QueryKind::kEdgeEdge, QueryKind::kVertexVertex,
                                 QueryKind::kVertexEdge})
      plans_[size_t(kind)] = plan_jobs(shapes_, kind);
    // The vertex side of a reversed job needs its vertex tree.
    for (const auto& plans : plans_)
      for (const JobPlan& plan : plans)
        if (plan.reversed) inputs[size_t(plan.query)].trees.vertices = true;
    for (GeometryInput& in : inputs) geometries_.push_back(std::make_unique<Geometry>(x_, std::move(in)));
    x_.finish();
    x_.release();
  }
  ~MeshStoreOn() override { x_.hold_for_teardown(); }

  void copy_edges(Edge* host_out) override {
    [[maybe_unused]] const auto scope = x_.scope();
    for (size_t g = 0; g < geometries_.size(); ++g) {
      Edge* out = host_out + first_[g].edges;
      geometries_[g]->copy_edges(x_, out);
      for (int32_t e = 0; e < geometries_[g]->num_edges(); ++e)
        for (int32_t& v : out[e].v) v += first_[g].vertices;
    }
  }

  void refit(const Strided& vertices) override { move_all(vertices, nullptr, false); }
  void rebuild(const Strided& vertices) override { move_all(vertices, nullptr, true); }
  void refit_swept(const Strided& x0, const Strided& x1) override { move_all(x0, &x1, false); }
  void rebuild_swept(const Strided& x0, const Strided& x1) override { move_all(x0, &x1, true); }
  void move_geometry(int32_t g, const Strided& x0, const Strided* x1, bool rebuild) override {
    [[maybe_unused]] const auto scope = x_.scope();
    geometries_[size_t(g)]->move(x_, x0, x1, rebuild);
    x_.finish();
  }
  bool swept() const override {
    for (const auto& g : geometries_)
      if (g->swept()) return true;
    return false;
  }

  double tree_growth() override {
    [[maybe_unused]] const auto scope = x_.scope();
    double growth = 0.0;
    for (const auto& g : geometries_) growth = std::max(growth, g->tree_growth());
    return growth;
  }

  uint64_t query(const QueryRequest& request, const PairOutput& out, WorkCounts* work) override {
    [[maybe_unused]] const auto scope = x_.scope();
    uint64_t total = 0;
    if (one_mesh()) {
      with_mesh_pass(request, out, [&](const auto& pass) { total = run_counted(x_, {work}, pass)[0]; });
    } else {
      with_job_pass(request, out, [&](const auto& pass) { total = run_counted(x_, {work}, pass)[0]; });
    }
    return total;
  }

  std::array<uint64_t, 2> query_vt_ee(const QueryJob& vt, const QueryJob& ee) override {
    [[maybe_unused]] const auto scope = x_.scope();
    std::array<uint64_t, 2> totals{};
    if (one_mesh()) {
      with_vt_pass(vt.request, vt.out, [&](const auto& vt_pass) {
        with_ee_pass(ee.request, ee.out,
                     [&](const auto& ee_pass) { totals = run_counted(x_, {vt.work, ee.work}, vt_pass, ee_pass); });
      });
    } else {
      // Two passes, one after the other: a fused pass of every VT and EE job shape pair would
      // multiply the kernels a CUDA build compiles, for one launch saved.
      with_job_pass(vt.request, vt.out, [&](const auto& pass) { totals[0] = run_counted(x_, {vt.work}, pass)[0]; });
      with_job_pass(ee.request, ee.out, [&](const auto& pass) { totals[1] = run_counted(x_, {ee.work}, pass)[0]; });
    }
    return totals;
  }

  // ---- Asynchronous calls ----------------------------------------------------------------------
  // Each geometry that moves reserves what its moves need; static ones fix their trees' nodes.
  // A scene of several geometries then writes the job tables of each kind for every arrangement
  // a stream-ordered move can reach (its moving geometries all at rest, or all swept where
  // reserved), so that its stream-ordered queries find theirs without an upload.
  void reserve(const Reservation& wanted) override {
    [[maybe_unused]] const auto scope = x_.scope();
    Reservation only_sort;
    only_sort.canonical_capacity = wanted.canonical_capacity;
    if ((wanted.refit || wanted.rebuild) && !reserved_.refit) x_.reserve_pending();  // also with no moving geometry
    for (size_t g = 0; g < geometries_.size(); ++g) geometries_[g]->reserve(x_, shapes_[g].role.is_static ? only_sort : wanted);
    reserved_.refit = reserved_.refit || wanted.refit || wanted.rebuild;
    reserved_.rebuild = reserved_.rebuild || wanted.rebuild;
    reserved_.swept = reserved_.swept || wanted.swept;
    reserved_.canonical_capacity = std::max(reserved_.canonical_capacity, wanted.canonical_capacity);
    if (!one_mesh()) {
      write_tables();
      std::vector<bool> swept(geometries_.size());
      for (size_t g = 0; g < geometries_.size(); ++g) swept[g] = geometries_[g]->swept();
      for (const bool moved_swept : {false, true}) {
        if (moved_swept && !reserved_.swept) continue;
        for (size_t g = 0; g < geometries_.size(); ++g)
          if (!shapes_[g].role.is_static) geometries_[g]->set_swept(moved_swept);
        write_tables();
      }
      for (size_t g = 0; g < geometries_.size(); ++g) geometries_[g]->set_swept(swept[g]);
    }
    x_.finish();
  }
  const Reservation& reservation() const override { return reserved_; }

  void refit_async(const Strided& vertices, Stream stream) override { move_async(vertices, nullptr, false, stream); }
  void rebuild_async(const Strided& vertices, Stream stream) override { move_async(vertices, nullptr, true, stream); }
  void refit_swept_async(const Strided& x0, const Strided& x1, Stream stream) override {
    move_async(x0, &x1, false, stream);
  }
  void rebuild_swept_async(const Strided& x0, const Strided& x1, Stream stream) override {
    move_async(x0, &x1, true, stream);
  }

  void query_async(const QueryRequest& request, const PairOutput& out, Stream stream) override {
    if (!one_mesh()) {
      prepare_async_tables({request.kind});
      [[maybe_unused]] const auto scope = x_.scope_on(stream);
      with_job_pass(request, out, [&](const auto& pass) { run_counted(x_, {nullptr}, pass); });
      return;
    }
    [[maybe_unused]] const auto scope = x_.scope_on(stream);
    mesh().fix_nodes(x_);
    with_mesh_pass(request, out, [&](const auto& pass) { run_counted(x_, {nullptr}, pass); });
  }

  void query_vt_ee_async(const QueryRequest& vt, const PairOutput& vt_out, const QueryRequest& ee,
                         const PairOutput& ee_out, Stream stream) override {
    if (!one_mesh()) {
      prepare_async_tables({vt.kind, ee.kind});
      [[maybe_unused]] const auto scope = x_.scope_on(stream);
      with_job_pass(vt, vt_out, [&](const auto& pass) { run_counted(x_, {nullptr}, pass); });
      with_job_pass(ee, ee_out, [&](const auto& pass) { run_counted(x_, {nullptr}, pass); });
      return;
    }
    [[maybe_unused]] const auto scope = x_.scope_on(stream);
    mesh().fix_nodes(x_);
    with_vt_pass(vt, vt_out, [&](const auto& vt_pass) {
      with_ee_pass(ee, ee_out, [&](const auto& ee_pass) { run_counted(x_, {nullptr, nullptr}, vt_pass, ee_pass); });
    });
  }

  PendingError take_pending_error(Stream stream) override {
    [[maybe_unused]] const auto scope = x_.scope();
    x_.wait(stream);
    return reserved_.refit ? x_.take_pending() : PendingError{};
  }

 private:
  // A geometry's first global ids.
  struct FirstIds {
    int32_t vertices = 0, triangles = 0, edges = 0;
  };
  // A scene of one geometry that reports its own pairs: today's one-mesh passes, no jobs.
  bool one_mesh() const { return geometries_.size() == 1 && shapes_[0].role.self; }
  Geometry& mesh() { return *geometries_[0]; }

  // Every geometry that moves to new positions: x0 (and x1) hold their vertices one after
  // another, in geometry order.
  void move_all(const Strided& x0, const Strided* x1, bool rebuild) {
    [[maybe_unused]] const auto scope = x_.scope();
    for_each_moving(x0, x1, [&](Geometry& g, const Strided& part0, const Strided* part1, int64_t) {
      g.move(x_, part0, part1, rebuild);
    });
    x_.finish();
  }
  // The stream-ordered form of move_all: each geometry checks its own vertices, so one with a
  // non-finite coordinate keeps its positions while the others take theirs; the pending error
  // names the vertex in the caller's buffer.
  void move_async(const Strided& x0, const Strided* x1, bool rebuild, Stream stream) {
    [[maybe_unused]] const auto scope = x_.scope_on(stream);
    for_each_moving(x0, x1, [&](Geometry& g, const Strided& part0, const Strided* part1, int64_t first) {
      g.move_async(x_, part0, part1, rebuild, first);
    });
  }
  // Calls fn(geometry, its part of x0, of x1 (or nullptr), where its part starts) for each
  // geometry that moves, in order.
  template <class Fn>
  void for_each_moving(const Strided& x0, const Strided* x1, Fn&& fn) {
    int64_t first = 0;
    for (size_t g = 0; g < geometries_.size(); ++g) {
      if (shapes_[g].role.is_static) continue;
      const int64_t n = shapes_[g].vertices;
      const Strided part0 = slice(x0, first, n);
      const Strided part1 = x1 ? slice(*x1, first, n) : Strided{};
      fn(*geometries_[g], part0, x1 ? &part1 : nullptr, first);
      first += n;
    }
  }
  static Strided slice(const Strided& values, int64_t first, int64_t count) {
    Strided part = values;
    part.data = static_cast<const char*>(values.data) + size_t(first) * values.stride;
    part.count = count;
    return part;
  }
  // The filters of geometry g's self pairs: its own incidence rule, and with a request, the
  // query's leaf test.
  uint32_t own_filters(size_t g) const { return shapes_[g].role.drop_incident ? kDropIncident : 0u; }
  uint32_t self_filters(size_t g, const QueryRequest& request) const {
    return (request.filters & kLeafExact) | own_filters(g);
  }

  // ---- One geometry: the one-mesh passes ----------------------------------------------------
  // Calls fn with the QueryPass of a request of any mesh kind.
  template <class Fn>
  void with_mesh_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    Geometry& g = mesh();
    const uint32_t filters = self_filters(0, request);
    switch (request.kind) {
      case QueryKind::kVertexTriangle: return with_vt_pass(request, out, fn);
      case QueryKind::kEdgeEdge: return with_ee_pass(request, out, fn);
      case QueryKind::kVertexEdge:
        return with_vertex_pass(request, g.edge_tree(), g.ev_queries(request.r, filters), out, fn);
      case QueryKind::kVertexVertex:
        return with_vertex_pass(request, g.vertex_tree(), g.vv_queries(request.r, filters), out, fn);
      default: fail(Status::kInternal, "not a mesh query kind");
    }
  }
  template <class Fn>
  void with_vt_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    Geometry& g = mesh();
    with_vertex_pass(request, g.triangle_tree(), g.vt_queries(request.r, self_filters(0, request)), out, fn);
  }
  // Vertex queries (VT, EV, VV): points, or swept each vertex's path, a segment: the segment
  // shapes, sphere mode as capsule_exact.
  template <class Queries, class Fn>
  void with_vertex_pass(const QueryRequest& request, const BvhView& tree, const Queries& queries,
                        const PairOutput& out, Fn&& fn) {
    const int32_t n = mesh().num_vertices();
    if (!swept()) return with_pass<true>(request, tree, queries, n, out, fn);
    with_pass<false>(swept_path(request), tree, queries, n, out, fn);
  }
  static QueryRequest swept_path(QueryRequest request) {
    if (request.mode == Mode::kSphere) request.mode = Mode::kCapsuleExact;
    return request;
  }
  template <class Fn>
  void with_ee_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    Geometry& g = mesh();
    with_pass<false>(request, g.edge_tree(), g.ee_queries(request.r, self_filters(0, request)), g.num_edges(), out, fn);
  }

  // ---- Many geometries: jobs (jobs.h) -------------------------------------------------------
  // A kind's jobs in executor memory, written for one layout of the geometries (the addresses
  // their sources read, and which are swept: GeometryOn::layout). The sources hold no radius
  // (JobPass gives it), so a table serves every query of its kind while that layout lasts.
  template <class Job>
  struct JobTable {
    std::vector<const void*> layout;
    Array<Job> jobs;
    int32_t num_jobs = 0, num_queries = 0;
  };
  // A kind's tables: those kept for stream-ordered queries (written by blocking calls only,
  // never rewritten: a captured graph reads them), and the last blocking query's.
  template <class Job>
  struct JobTables {
    using Type = Job;
    std::vector<std::unique_ptr<JobTable<Job>>> kept;
    JobTable<Job> last;
  };

  std::vector<const void*> layout() const {
    std::vector<const void*> key;
    for (const auto& g : geometries_) g->layout(key);
    return key;
  }
  // The table of Job's kind for the geometries' layout now: a kept one, else the last one
  // (rewritten when the layout changed) or, with keep, a new kept one.
  template <class Job>
  const JobTable<Job>& table(JobTables<Job>& tables, bool keep) {
    const std::vector<const void*> key = layout();
    if (const JobTable<Job>* kept = kept_table(tables, key)) return *kept;
    if (!keep && tables.last.layout == key) return tables.last;
    if (keep) tables.kept.push_back(std::make_unique<JobTable<Job>>());
    JobTable<Job>& t = keep ? *tables.kept.back() : tables.last;
    std::vector<Job> jobs = kind_jobs<Job>();
    t.num_jobs = int32_t(jobs.size());
    t.num_queries = 0;
    for (const Job& job : jobs) t.num_queries += job.num_queries;
    x_.upload(t.jobs, std::move(jobs));
    t.layout = key;
    return t;
  }
  // Every kind's kept table for the layout now (a blocking call's work).
  void write_tables() {
    table(vt_tables_, true);
    table(ev_tables_, true);
    table(vv_tables_, true);
    table(ee_tables_, true);
  }
  // The kept table written for `key`, if any.
  template <class Job>
  static const JobTable<Job>* kept_table(const JobTables<Job>& tables, const std::vector<const void*>& key) {
    for (const auto& kept : tables.kept)
      if (kept->layout == key) return kept.get();
    return nullptr;
  }
  // Before a stream-ordered query: every tree's nodes fixed and the kept tables of its kinds
  // for the layout now, made here (allocating and synchronising, outside the stream's order)
  // unless a reservation or an earlier call made them. Where they are there (every step after
  // the first), it does no device work and does not synchronise.
  void prepare_async_tables(std::initializer_list<QueryKind> kinds) {
    bool ready = true;
    for (const auto& g : geometries_) ready = ready && g->nodes_fixed();
    if (ready) {
      const std::vector<const void*> key = layout();
      for (const QueryKind kind : kinds)
        with_tables(kind, [&](const auto& tables) { ready = ready && kept_table(tables, key) != nullptr; });
    }
    if (ready) return;
    [[maybe_unused]] const auto scope = x_.scope();
    for (const auto& g : geometries_) g->fix_nodes(x_);
    for (const QueryKind kind : kinds) with_tables(kind, [&](auto& tables) { table(tables, true); });
    x_.finish();
  }
  // Calls fn with the tables of a mesh kind.
  template <class Fn>
  void with_tables(QueryKind kind, Fn&& fn) {
    switch (kind) {
      case QueryKind::kVertexTriangle: return fn(vt_tables_);
      case QueryKind::kVertexEdge: return fn(ev_tables_);
      case QueryKind::kVertexVertex: return fn(vv_tables_);
      case QueryKind::kEdgeEdge: return fn(ee_tables_);
      default: fail(Status::kInternal, "not a mesh query kind");
    }
  }

  // Calls fn with the JobPass of a request: its kind's table for the layout now, the query's
  // radius and leaf test, point shapes for vertex queries unless a geometry is swept (then each
  // vertex's path: segment shapes).
  template <class Fn>
  void with_job_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    with_tables(request.kind, [&](auto& tables) {
      using Job = typename std::decay_t<decltype(tables)>::Type;
      const JobTable<Job>& t = table(tables, false);
      const bool vertex_queries = request.kind != QueryKind::kEdgeEdge;
      const int32_t first_bound = vertex_queries ? totals_.vertices : totals_.edges;
      auto with = [&](auto points, const QueryRequest& r) {
        with_shape<decltype(points)::value>(r.mode, [&](auto shape) {
          fn(JobPass<decltype(shape), Job>{r.kind, t.jobs.data(), t.num_jobs, t.num_queries, first_bound, out, r.r,
                                           r.filters & kLeafExact});
        });
      };
      if (!vertex_queries) return with(std::false_type{}, request);
      if (!swept()) return with(std::true_type{}, request);
      with(std::false_type{}, swept_path(request));
    });
  }
  // A kind's jobs on the host (Job names the kind), in plan order, without the query's radius
  // and leaf test.
  template <class Job>
  std::vector<Job> kind_jobs() {
    if constexpr (std::is_same<Job, VtJob>::value || std::is_same<Job, EvJob>::value) {
      using Prim = typename Job::Reversed::Prim;
      constexpr bool kTriangles = std::is_same<Prim, Triangle>::value;
      const auto kind = kTriangles ? QueryKind::kVertexTriangle : QueryKind::kVertexEdge;
      return make_jobs<Job>(plans_[size_t(kind)], [&](Job& job, Geometry& q, Geometry& t, size_t qi, size_t ti) {
        return fill_vertex_job(job, q, t, first_[qi].vertices, kTriangles ? first_[ti].triangles : first_[ti].edges,
                               own_filters(qi));
      });
    } else if constexpr (std::is_same<Job, VvJob>::value) {
      return make_jobs<Job>(plans_[size_t(QueryKind::kVertexVertex)], [&](Job& job, Geometry& q, Geometry& t, size_t qi, size_t ti) {
        job.bvh = t.vertex_tree();
        job.first_offset = first_[qi].vertices;
        job.second_offset = first_[ti].vertices;
        job.swap = first_[qi].vertices > first_[ti].vertices;
        if (job.self) job.self_queries = q.vv_queries(0.0f, own_filters(qi));
        else job.cross_queries = {q.side(), t.side(), 0.0f, 0u, !job.swap};
        return q.num_vertices();
      });
    } else {
      return make_jobs<Job>(plans_[size_t(QueryKind::kEdgeEdge)], [&](Job& job, Geometry& q, Geometry& t, size_t qi, size_t ti) {
        job.bvh = t.edge_tree();
        job.first_offset = first_[qi].edges;
        job.second_offset = first_[ti].edges;
        job.swap = first_[qi].edges > first_[ti].edges;
        if (job.self) job.self_queries = q.ee_queries(0.0f, own_filters(qi));
        else job.cross_queries = {q.side(), t.side(), q.leaf_edges(), q.edge_tree().sorted_prims, t.leaf_edges(),
                                  0.0f, 0u, !job.swap};
        return q.num_edges();
      });
    }
  }
  // A VT or EV job (Job's cross source names the primitive): q's vertices against t's
  // triangles or edges, or reversed, those against q's vertex tree; returns its query count.
  template <class Job>
  int32_t fill_vertex_job(Job& job, Geometry& q, Geometry& t, int32_t first_vertex, int32_t first_prim,
                          uint32_t self_filters) {
    using Prim = typename Job::Reversed::Prim;
    job.first_offset = first_vertex;
    job.second_offset = first_prim;
    if (job.reversed) {
      job.bvh = q.vertex_tree();
      job.reversed_queries = {q.side(), t.side(), t.template leaf_prims<Prim>(), t.template prim_tree<Prim>().sorted_prims,
                              0.0f, 0u, q.max_thickness()};
      return t.template num_prims<Prim>();
    }
    job.bvh = t.template prim_tree<Prim>();
    if (job.self) job.self_queries = q.template vertex_prim_queries<Prim>(0.0f, self_filters);
    else job.cross_queries = {q.side(), t.side(), t.template leaf_prims<Prim>(), q.vertex_order(), 0.0f, 0u};
    return q.num_vertices();
  }
  // A kind's jobs on the host, in plan order: fill(job, query geometry, tree geometry, their
  // indices) sets the tree, offsets and source and returns the job's query count.
  template <class Job, class Fill>
  std::vector<Job> make_jobs(const std::vector<JobPlan>& plans, Fill&& fill) {
    std::vector<Job> jobs;
    jobs.reserve(plans.size());
    int32_t first_query = 0;
    for (const JobPlan& plan : plans) {
      Job job{};
      job.self = plan.query == plan.tree;
      job.reversed = plan.reversed;
      job.first_query = first_query;
      job.num_queries = fill(job, *geometries_[size_t(plan.query)], *geometries_[size_t(plan.tree)],
                             size_t(plan.query), size_t(plan.tree));
      first_query += job.num_queries;
      jobs.push_back(job);
    }
    return jobs;
  }

  X x_;  // first: holds its device while the members below are created and destroyed
  std::vector<std::unique_ptr<Geometry>> geometries_;
  std::vector<GeometryShape> shapes_;
  std::vector<FirstIds> first_;  // each geometry's first global ids
  FirstIds totals_;              // the scene's counts
  std::array<std::vector<JobPlan>, kQueryKinds> plans_;  // each mesh kind's jobs
  JobTables<VtJob> vt_tables_;
  JobTables<EvJob> ev_tables_;
  JobTables<EeJob> ee_tables_;
  JobTables<VvJob> vv_tables_;
  Reservation reserved_;  // what reserve() has reserved, for the scene
};

template <class X>
class BoxStoreOn final : public Store {
  static_assert(ExecutorContract<X>::value, "a store runs on an executor (executor.h)");
  template <class T>
  using Array = typename X::template Array<T>;

 public:
  BoxStoreOn(typename X::Device device, const Strided& boxes) : x_(device), num_boxes_(int32_t(boxes.count)) {
    x_.hold();
    x_.gather(boxes, boxes_);
    tree_.build(GivenBoxes{boxes_.data()}, num_boxes_);
    x_.finish();
    x_.release();
  }
  ~BoxStoreOn() override { x_.hold_for_teardown(); }

  void refit(const Strided& boxes) override {
    [[maybe_unused]] const auto scope = x_.scope();
    x_.gather(boxes, boxes_);
    tree_.refit(GivenBoxes{boxes_.data()});
    x_.finish();
  }

  void rebuild(const Strided& boxes) override {
    [[maybe_unused]] const auto scope = x_.scope();
    x_.gather(boxes, boxes_);
    tree_.build(GivenBoxes{boxes_.data()}, num_boxes_);
    x_.finish();
  }

  double tree_growth() override {
    [[maybe_unused]] const auto scope = x_.scope();
    return tree_growth_of(tree_);
  }

  uint64_t query(const QueryRequest& request, const PairOutput& out, WorkCounts* work) override {
    [[maybe_unused]] const auto scope = x_.scope();
    x_.gather(request.first, query_first_);
    x_.gather(request.second, query_second_);
    const UserQueries queries{query_first_.data(), request.second.count == 0 ? nullptr : query_second_.data(),
                              request.r};
    const int32_t n = int32_t(request.first.count);
    uint64_t total = 0;
    auto run = [&](const auto& pass) { total = run_counted(x_, {work}, pass)[0]; };
    if (request.kind == QueryKind::kUserSpheres) with_pass<true>(request, tree_.view(), queries, n, out, run);
    else with_pass<false>(request, tree_.view(), queries, n, out, run);
    return total;
  }

 private:
  X x_;  // first: holds its device while the members below are created and destroyed
  Array<Box> boxes_;
  int32_t num_boxes_;
  typename X::Tree tree_;
  Array<Vec3> query_first_, query_second_;  // the last queries' points, kept to be reused
};

}  // namespace minkq
