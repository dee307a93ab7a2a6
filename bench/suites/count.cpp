// minkq_bench's count suite (count.md): what a count-only query (MINKQ_QUERY_COUNT) costs
// against the queries that store their pairs, through the C API on one device, in the same run:
// per scene (each created at its last frame, r = the scene's radius, incident pairs dropped) and
// query (VT sphere, EE box, and both with leaf_exact), the count alone, a query into a caller's
// buffer of exactly the count, and into a reused library-owned result. The two-pass sizing a
// caller does (count, then query into a buffer of that size) is the first and second rows
// together. Checked: every count equals the stored query's.
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "suites/suites.h"

namespace minkq::bench::suites {
namespace {

struct Case {
  const char* name;
  minkq_query_kind kind;
  minkq_mode mode;
  uint32_t flags;
};
constexpr Case kCases[] = {{"VT sphere", MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 0},
                           {"EE box", MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0},
                           {"VT box + leaf_exact", MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT},
                           {"EE box + leaf_exact", MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT}};

uint64_t count_of(minkq_scene* scene, const Case& c, float r) {
  const minkq_query_desc q{c.kind, c.mode, c.flags | MINKQ_QUERY_COUNT, r};
  minkq_query_info info{};
  check(minkq_scene_query(scene, &q, nullptr, 0, MINKQ_MEMORY_HOST, &info), "count-only minkq_scene_query");
  return info.count;
}

// Rows of one scene; ok turns false where a count differs from the stored query's.
std::string compare(const SceneFrames& sc, minkq_device* device, int repeats, bool& ok) {
  const float r = float(sc.radius_factor * sc.mean_edge);
  std::fprintf(stderr, "%s: %d T, r = %.4g\n", sc.name.c_str(), int(sc.mesh.triangle_count()), double(r));
  Scene scene = create_scene(device, sc.frames.back(), sc.mesh.tris);
  Result result = new_result();
  std::string out;
  for (const Case& c : kCases) {
    const minkq_query_desc stored{c.kind, c.mode, c.flags, r};
    const uint64_t n = count_of(scene.get(), c, r);
    std::vector<int32_t> buffer(2 * n + 2);
    minkq_query_info info{};
    auto into_buffer = [&] {
      check(minkq_scene_query(scene.get(), &stored, buffer.data(), n, MINKQ_MEMORY_HOST, &info), "minkq_scene_query");
    };
    auto into_result = [&] { check(minkq_scene_query_result(scene.get(), &stored, result.get()), "query_result"); };
    into_buffer();
    into_result();
    if (info.count != n || minkq_result_count(result.get()) != n) {
      std::fprintf(stderr, "FAIL %s %s: count %llu, stored %llu, result %llu\n", sc.name.c_str(), c.name,
                   (unsigned long long)n, (unsigned long long)info.count,
                   (unsigned long long)minkq_result_count(result.get()));
      ok = false;
    }
    const Timing counted = measure(1, repeats, [&] { count_of(scene.get(), c, r); });
    const Timing written = measure(1, repeats, into_buffer);
    const Timing kept = measure(1, repeats, into_result);
    auto row = [&](const char* variant, const Timing& t) {
      out += "| " + sc.name + " | " + std::to_string(sc.mesh.triangle_count()) + " | " + c.name + " | " +
             std::to_string(n) + " | " + variant + " | " + t.text(4) + " | " + fmt(t.median / written.median, 3) +
             "x |\n";
    };
    row("MINKQ_QUERY_COUNT", counted);
    row("into a buffer of the count", written);
    row("into a reused minkq_result", kept);
  }
  return out;
}

}  // namespace

std::string count_report(const SuiteRun& run, bool large, bool& ok) {
  const std::string backend = minkq_device_name(run.device);
  std::ostringstream o;
  o << "# Count-only queries (issue 27)\n\nMachine: " << run.machine << ". Load average (1 min) at start "
    << fmt(load_average(), 3) << ". Each scene created at its last frame, r = "
    << "the scene's radius, incident pairs dropped; per query one warm-up and " << run.repeats << " timed runs of each "
    << "variant (ms: median and range); '/ stored' = this ms over the query into a buffer of the count, in the "
    << "same run. A caller that sizes its buffer first pays the COUNT row and then the buffer row. Counts checked "
    << "equal to the stored queries'. Device: " << backend << ". Written " << utc_now() << " by " << run.by << ".\n\n"
    << "| scene | triangles | query | pairs | variant | ms | / stored |\n|---|---|---|---|---|---|---|\n";
  const double scale = run.quick ? 2e3 : 0;  // reference sizes
  for (const std::string& name : procedural_scene_names())
    o << compare(make_scene(name, scale, 1, run.data), run.device, run.repeats, ok);
  o << compare(make_scene("twist_target", scale, 1, run.data), run.device, run.repeats, ok);
  if (large) o << compare(make_scene("twist_target", 1e6, 1, run.data), run.device, run.repeats, ok);
  o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
  return o.str();
}

}  // namespace minkq::bench::suites
