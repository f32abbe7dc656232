// The 3D Delaunay kernel alone: points per second and bytes per tet on
// uniform random points and on a regular grid (every cube's 8 corners
// cospherical: the perturbation decides all ties).
//   bench_delaunay [random N]... [grid K]...   (default: random 1000000, grid 100)
// Prints one line per run: kind, points, tets, seconds, points/s, mesh bytes
// per tet (arrays' capacity) and the process's peak resident bytes per tet;
// then the CPU time (the machine may be shared: compare that one), the points
// per CPU second, and how many predicate calls fell through the filter.
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/generate/delaunay3d.hpp"

namespace {

double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

long peak_rss_bytes() {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atol(line.c_str() + 6) * 1024;
  return 0;
}

void run(const std::string& kind, std::vector<cm::Vec3> pts) {
  cm::mesh::TetMesh m;
  m.coords = std::move(pts);
  const std::size_t n = m.coords.size();
  m.resize_vertex_arrays();
  cm::Vec3 lo = m.coords[0], hi = m.coords[0];
  for (const auto& p : m.coords) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  std::vector<cm::VertId> ids(n);
  for (std::size_t i = 0; i < n; ++i) ids[i] = static_cast<cm::VertId>(i);
  cm::predicates::exact_stats() = {};
  const double c0 = cpu_seconds();
  const auto t0 = std::chrono::steady_clock::now();
  cm::generate::Delaunay3d dt(m, lo, hi);
  dt.insert_all(ids);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double cpu = cpu_seconds() - c0;
  const auto ex = cm::predicates::exact_stats();
  const std::size_t tets = dt.editor().live_tets();
  fmt::print("{:<8} points {:>9}  tets {:>10}  {:7.2f} s  {:9.0f} points/s  mesh {:5.1f} B/tet  peak RSS {:5.1f} B/tet\n",
             kind, n, tets, s, n / s, double(m.memory_bytes()) / tets, double(peak_rss_bytes()) / tets);
  fmt::print("         cpu {:7.2f} s  {:9.0f} points/cpu-s  exact stage: orient3d {}  insphere {}  "
             "walk steps {:.2f}/point\n",
             cpu, n / cpu, ex.orient3d, ex.insphere, double(dt.exact_walk_steps()) / n);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::pair<std::string, long>> runs;
  for (int i = 1; i + 1 < argc; i += 2) runs.emplace_back(argv[i], std::atol(argv[i + 1]));
  if (runs.empty()) runs = {{"random", 1000000}, {"grid", 100}};
  for (const auto& [kind, n] : runs) {
    std::vector<cm::Vec3> pts;
    if (kind == "random") {
      std::mt19937_64 rng(1);
      std::uniform_real_distribution<double> u(0, 1);
      pts.resize(static_cast<std::size_t>(n));
      for (auto& p : pts) p = cm::Vec3(u(rng), u(rng), u(rng));
    } else if (kind == "grid") {
      for (long i = 0; i < n; ++i)
        for (long j = 0; j < n; ++j)
          for (long k = 0; k < n; ++k) pts.emplace_back(double(i), double(j), double(k));
    } else {
      std::fprintf(stderr, "unknown kind '%s' (random N | grid K)\n", kind.c_str());
      return 2;
    }
    run(kind, std::move(pts));
  }
  return 0;
}
