// A small timing harness (warm-up, repeats, median and spread) and the facts that name the
// machine in every result file. Google Benchmark is not used: each measurement here also has to
// hand back what it produced (candidate sets, counts) for the accuracy columns, and the tables
// need medians of a handful of repeats of multi-millisecond calls, which this does directly.
#pragma once

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace minkq::bench {

inline double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Timing {
  double median = 0, min = 0, max = 0;
  int repeats = 0;
  // "12.3 (11.9-13.0)": median and the range of the repeats.
  std::string text(int digits = 3) const {
    char b[96];
    if (repeats <= 1)
      std::snprintf(b, sizeof b, "%.*g", digits, median);
    else
      std::snprintf(b, sizeof b, "%.*g (%.*g–%.*g)", digits, median, digits, min, digits, max);
    return b;
  }
};

// The median of a non-empty set of values (any order): the middle one, or the mean of the two.
inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Median and range of a non-empty set of times (any order).
inline Timing summarize(const std::vector<double>& t) {
  Timing out;
  out.repeats = int(t.size());
  out.min = *std::min_element(t.begin(), t.end());
  out.max = *std::max_element(t.begin(), t.end());
  out.median = median(t);
  return out;
}

// Runs fn warmup times untimed, then repeats times timed; each run may do untimed set-up in
// before() (e.g. restoring state). Returns median and range in milliseconds.
template <class Fn, class Before>
Timing measure(int warmup, int repeats, Fn&& fn, Before&& before) {
  for (int i = 0; i < warmup; ++i) {
    before();
    fn();
  }
  std::vector<double> t;
  for (int i = 0; i < std::max(1, repeats); ++i) {
    before();
    const double start = now_ms();
    fn();
    t.push_back(now_ms() - start);
  }
  return summarize(t);
}
template <class Fn>
Timing measure(int warmup, int repeats, Fn&& fn) {
  return measure(warmup, repeats, fn, [] {});
}

// 1-minute load average (the machine is shared: every result records it).
inline double load_average() {
  std::ifstream f("/proc/loadavg");
  double l = -1;
  f >> l;
  return l;
}

inline std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("model name", 0) == 0) {
      const size_t colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  return "unknown CPU";
}

inline int online_cpus() {
  int n = 0;
  std::ifstream f("/proc/cpuinfo");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("processor", 0) == 0) ++n;
  return n;
}

// Resident set size in bytes (from /proc/self/statm).
inline double resident_bytes() {
  std::ifstream f("/proc/self/statm");
  double size = 0, resident = 0;
  f >> size >> resident;
  return resident * 4096.0;
}

inline std::string fmt(double v, int digits = 3) {
  if (!std::isfinite(v)) return "–";
  char b[48];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}
inline std::string fmt_count(double v) {
  char b[48];
  if (v >= 999500)
    std::snprintf(b, sizeof b, "%.3gM", v / 1e6);
  else if (v >= 1e4)
    std::snprintf(b, sizeof b, "%.3gk", v / 1e3);
  else
    std::snprintf(b, sizeof b, "%.0f", v);
  return b;
}

// Geometric mean of the finite, positive values of v (NaN where there are none): speed-up and
// count ratios over scenes.
inline double geomean(const std::vector<double>& v) {
  double s = 0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x) && x > 0) s += std::log(x), ++n;
  return n ? std::exp(s / n) : NAN;
}

// The non-empty items of a comma-separated list ("a,b,,c": a, b, c): the options' lists.
inline std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

// The time a result file is written, "2026-12-06 08:13 UTC".
inline std::string utc_now() {
  char when[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  return when;
}

}  // namespace minkq::bench
