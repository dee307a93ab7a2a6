// Checks `minkq query MESH0 --to MESH1`: two OBJ frames of a twisted sheet far from the origin
// (coordinates printed with 17 digits, so only a double reading keeps them), a motion of a few
// edge lengths; in every swept mode the pairs it writes contain every pair the double oracle
// finds within r at 33 times of the step, and r = 0 is accepted. Also that leaf_exact and a
// frame of another mesh are refused.
// usage: check_swept_output MINKQ_BINARY WORK_DIR
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "contact_checks.h"
#include "swept_steps.h"

namespace ref = minkq::reference;

void write_obj(const std::string& path, const ref::Mesh& m) {
  std::ofstream f(path);
  char line[128];
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", m.xyz64[3 * v], m.xyz64[3 * v + 1], m.xyz64[3 * v + 2]);
    f << line;
  }
  for (size_t t = 0; t < m.triangle_count(); ++t)
    f << "f " << m.tris[3 * t] + 1 << " " << m.tris[3 * t + 1] + 1 << " " << m.tris[3 * t + 2] + 1 << "\n";
  if (!f) throw std::runtime_error("cannot write " + path);
}

// The sheet at 3e3 + x / 1e3 with a motion of `amount` edge lengths.
ref::Mesh frame(double amount) {
  ref::Mesh m = ref::twisted_sheet(14, 2.0);
  const double h = ref::mean_edge_length(m);
  std::vector<double> xyz(m.xyz.size());
  for (size_t i = 0; i < xyz.size(); ++i)
    xyz[i] = 3e3 + (double(m.xyz[i]) + amount * h * std::sin(0.31 * double(i / 3) + 1.3 * double(i % 3))) * 1e-3;
  ref::set_float64(m, std::move(xyz));
  return m;
}

int run(const std::string& command) {
  std::printf("%s\n", command.c_str());
  std::fflush(stdout);
  return std::system(command.c_str());
}

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: check_swept_output MINKQ_BINARY WORK_DIR\n");
    return 2;
  }
  try {
    const std::string binary = argv[1], work = argv[2];
    const minkq::test::Step step{frame(0.0), frame(2.5)};
    write_obj(work + "/frame0.obj", step.from);
    write_obj(work + "/frame1.obj", step.to);
    const std::string base = "\"" + binary + "\" query \"" + work + "/frame0.obj\" --to \"" + work + "/frame1.obj\"";
    int failures = 0;
    for (double factor : {0.5, 0.0}) {
      const double r = double(float(factor * ref::mean_edge_length(step.from)));
      const auto [vt_truth, ee_truth] = minkq::test::sampled_contacts(step, r, 32);
      for (const char* mode : {"box", "capsule_ray", "capsule_exact"}) {
        char radius[32];
        std::snprintf(radius, sizeof radius, "%.9g", r);
        const std::string prefix = work + "/swept_" + mode;
        if (run(base + " --radius " + radius + " --mode " + mode + " --backend cpu --out \"" + prefix + "\"") != 0)
          throw std::runtime_error("minkq query --to failed");
        for (const auto& [kind, truth] : {std::pair{"vt", vt_truth}, std::pair{"ee", ee_truth}}) {
          const ref::Pairs got = minkq::test::read_pairs(prefix + "." + kind + ".bin");
          ref::Pairs missing;
          std::set_difference(truth.begin(), truth.end(), got.begin(), got.end(), std::back_inserter(missing));
          std::printf("%s r %g %s: %zu reported, %zu found by the sampled oracle, %zu missing\n", mode, r, kind,
                      got.size(), truth.size(), missing.size());
          failures += int(missing.size());
          if (factor > 0 && truth.empty()) {
            std::printf("the step should bring elements within r\n");
            ++failures;
          }
        }
      }
    }
    for (const char* leaf_exact : {"--leaf-exact", "--mode leaf_exact"})  // the switch and the old word
      if (run(base + " --radius 0.001 " + leaf_exact + " --backend cpu") != 2 * 256) {  // exit status 2 (usage)
        std::printf("%s with --to should be refused\n", leaf_exact);
        ++failures;
      }
    ref::Mesh other = ref::twisted_sheet(5, 1.0);
    ref::set_float64(other, std::vector<double>(other.xyz.begin(), other.xyz.end()));
    write_obj(work + "/other.obj", other);
    const std::string mismatch = "\"" + binary + "\" query \"" + work + "/frame0.obj\" --to \"" + work +
                                 "/other.obj\" --radius 0.001 --backend cpu";
    if (run(mismatch) != 3 * 256) {  // exit status 3 (failure), naming the frame
      std::printf("a frame of another mesh should be refused\n");
      ++failures;
    }
    return failures == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "check_swept_output: %s\n", e.what());
    return 3;
  }
}
