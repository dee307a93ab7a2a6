// minkq_idle_probe: how much of a second core a short parallel run gets after the machine sat
// idle, with no minkq code at all. The same fixed work (a dependent floating-point loop, in
// chunks) runs on one thread, then on two (TBB's parallel_for, and a plain std::thread woken
// through a condition variable), each run after a sleep of 0, 1, 2, 5, 20 or 50 ms. On a machine
// that gives both cores at once, two threads take about half the one-thread time after any
// sleep. Where the two-thread median after a sleep sits near the one-thread time, the second
// core was not there for most of those runs (on the 2-vCPU VMs here the kernel packs work onto
// one vCPU after idle), so every benchmark whose runs last a few ms after an idle gap
// (arborx_bench's 5 ms gaps between contestants) measures some rounds at one core's speed:
// read its medians with this table beside them.
//
//   minkq_idle_probe [--work-ms T] [--rounds N] [--out FILE]   (defaults: 3 ms, 40 rounds)
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "harness.h"

namespace mb = minkq::bench;

namespace {

constexpr int kChunks = 256;
std::atomic<double> g_sink{0.0};

double chunk(int64_t steps) {
  double s = 1.0;
  for (int64_t i = 0; i < steps; ++i) s = std::sqrt(s + double(i));
  return s;
}
void run_chunks(int first, int last, int64_t steps) {
  double s = 0.0;
  for (int c = first; c < last; ++c) s += chunk(steps);
  g_sink = g_sink + s;
}

// A second thread that runs the upper half of the chunks each time it is woken.
class Partner {
 public:
  explicit Partner(int64_t steps) : steps_(steps), thread_([this] { loop(); }) {}
  ~Partner() {
    { std::lock_guard<std::mutex> lock(m_); stop_ = true; }
    cv_.notify_all();
    thread_.join();
  }
  void run() {
    { std::lock_guard<std::mutex> lock(m_); ++go_; }
    cv_.notify_all();
    run_chunks(0, kChunks / 2, steps_);
    std::unique_lock<std::mutex> lock(m_);
    cv_.wait(lock, [&] { return done_ == go_; });
  }

 private:
  void loop() {
    int seen = 0;
    std::unique_lock<std::mutex> lock(m_);
    while (true) {
      cv_.wait(lock, [&] { return go_ > seen || stop_; });
      if (stop_) return;
      seen = go_;
      lock.unlock();
      run_chunks(kChunks / 2, kChunks, steps_);
      lock.lock();
      ++done_;
      cv_.notify_all();
    }
  }
  int64_t steps_;
  std::mutex m_;
  std::condition_variable cv_;
  int go_ = 0, done_ = 0;
  bool stop_ = false;
  std::thread thread_;
};

template <class Run>
mb::Timing rounds(int n, int sleep_ms, const Run& run) {
  std::vector<double> ms;
  for (int k = 0; k < n; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(sleep_ms));
    const double t0 = mb::now_ms();
    run();
    ms.push_back(mb::now_ms() - t0);
  }
  return mb::summarize(ms);
}

}  // namespace

int main(int argc, char** argv) {
  double work_ms = 3.0;
  int n = 40;
  std::string out;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--work-ms" && i + 1 < argc) work_ms = std::atof(argv[++i]);
    else if (a == "--rounds" && i + 1 < argc) n = std::atoi(argv[++i]);
    else if (a == "--out" && i + 1 < argc) out = argv[++i];
    else {
      std::fprintf(stderr, "usage: minkq_idle_probe [--work-ms T] [--rounds N] [--out FILE]\n");
      return a == "--help" ? 0 : 2;
    }
  }
  if (work_ms <= 0 || n < 1) {
    std::fprintf(stderr, "minkq_idle_probe: --work-ms must be > 0 and --rounds >= 1\n");
    return 2;
  }
  tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
  // Steps per chunk so that one thread takes about work_ms over all chunks (calibrated warm).
  int64_t steps = 1000;
  for (int k = 0; k < 8; ++k) {
    const double t0 = mb::now_ms();
    run_chunks(0, kChunks, steps);
    const double t = mb::now_ms() - t0;
    steps = std::max<int64_t>(1, int64_t(double(steps) * work_ms / std::max(t, 1e-3)));
  }
  std::ostringstream md;
  md << "# Two threads after an idle sleep (minkq_idle_probe)\n\n"
     << "Load average (1 min) at start " << mb::load_average() << ". Work: " << kChunks
     << " chunks, about " << work_ms << " ms on one thread; " << n
     << " rounds per row, each after the sleep; ms = median (range). speed-up = one-thread median / "
        "this row's median (2 = both cores the whole run).\n\n"
     << "| sleep before each run | one thread | TBB parallel_for, 2 threads | speed-up | std::thread pair | speed-up |\n"
     << "|---|---|---|---|---|---|\n";
  Partner partner(steps);
  auto ratio = [](double a, double b) {
    char r[32];
    std::snprintf(r, sizeof r, "%.2fx", a / b);
    return std::string(r);
  };
  for (const int sleep_ms : {0, 1, 2, 5, 20, 50}) {
    const mb::Timing one = rounds(n, sleep_ms, [&] { run_chunks(0, kChunks, steps); });
    const mb::Timing tbb2 = rounds(n, sleep_ms, [&] {
      tbb::parallel_for(0, kChunks, [&](int c) { run_chunks(c, c + 1, steps); });
    });
    const mb::Timing pair = rounds(n, sleep_ms, [&] { partner.run(); });
    md << "| " << sleep_ms << " ms | " << one.text() << " | " << tbb2.text() << " | " << ratio(one.median, tbb2.median)
       << " | " << pair.text() << " | " << ratio(one.median, pair.median) << " |\n";
  }
  std::cout << md.str();
  if (!out.empty()) {
    std::ofstream f(out);
    f << md.str();
    if (!f) {
      std::fprintf(stderr, "minkq_idle_probe: cannot write %s\n", out.c_str());
      return 1;
    }
  }
  return 0;
}
