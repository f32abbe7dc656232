// Boundary (surface) meshing of every shared model with the default sizes
// (hmax = diagonal / 20, hmin = hmax / 100, curvature alpha = 0.04, about 20
// edges per circle), side by side with `gmsh -2` given the same sizes
// (MeshSizeMax, MeshSizeMin, MeshSizeFromCurvature 20) when Gmsh is
// installed. Prints one line per model: triangles, wall time, min and mean
// triangle mean ratio for both, and Gmsh's time over ours. Our time includes
// the size field (curvature sampling, octree) and the checks are not timed.
// The last columns run Gmsh again with its sizes scaled (Mesh.MeshSizeFactor)
// until its triangle count is within 15% of ours.
// Gmsh is stopped after kGmshSeconds. Models are read from $CM_MODELS_DIR, by default ../../shared/models.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "curvemesh/generate/boundary_mesh.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "shared_models.hpp"
#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/size/build.hpp"

namespace {

namespace fs = std::filesystem;

struct Row {
  std::size_t triangles = 0;
  double seconds = 0, min_q = 0, mean_q = 0;
  bool ok = false;
};

void measure(const cm::mesh::TetMesh& m, Row& r) {
  r.triangles = m.tris.size();
  double sum = 0, lo = 1;
  for (const auto& t : m.tris) {
    const double q = cm::quality::triangle_mean_ratio(m.coords[t.verts[0]], m.coords[t.verts[1]], m.coords[t.verts[2]]);
    sum += q;
    lo = std::min(lo, q);
  }
  r.min_q = lo;
  r.mean_q = m.tris.empty() ? 0 : sum / m.tris.size();
}

// Gmsh gets this long per model (it can spend many minutes on sliver faces).
constexpr int kGmshSeconds = 300;

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main() {
  const std::vector<fs::path> files = cm::bench::model_files();
  const bool have_gmsh = std::system("gmsh --version > /dev/null 2>&1") == 0;
  const fs::path tmp = fs::temp_directory_path() / "curvemesh_bench_surface";
  fs::create_directories(tmp);
  fmt::print("{:<36} {:>9} {:>8} {:>6} {:>6} | {:>9} {:>8} {:>6} {:>6} | {:>7} | {:>6} {:>9} {:>8} {:>6} {:>6} | {:>7}\n",
             "model", "tris", "s", "minq", "meanq", "gmsh tris", "s", "minq", "meanq", "gmsh/us", "factor", "gmsh tris",
             "s", "minq", "meanq", "gmsh/us");
  for (const fs::path& f : files) {
    Row ours, theirs;
    double hmin = 0, hmax = 0;
    std::string units;
    try {
      const auto model = cm::geom_occ::load_model(f.string());
      const double t0 = now();
      const cm::size::SizeFieldResult sf = cm::size::build_size_field(*model, {});
      const cm::mesh::TetMesh m = cm::generate::mesh_boundary(*model, *sf.field);
      ours.seconds = now() - t0;
      ours.ok = true;
      hmin = sf.hmin;
      hmax = sf.hmax;
      units = model->units();
      measure(m, ours);
    } catch (const std::exception& e) {
      fmt::print("{:<36} error: {}\n", f.filename().string(), e.what());
      continue;
    }
    auto run_gmsh = [&](double factor) {
      Row g;
      const fs::path out = tmp / (f.stem().string() + "_gmsh.msh");
      const std::string cmd = fmt::format(
          "timeout {} gmsh -2 '{}' -o '{}' -format msh41 -setnumber Mesh.MeshSizeMax {} -setnumber Mesh.MeshSizeMin {} "
          "-setnumber Mesh.MeshSizeFromCurvature 20 -setnumber Mesh.MeshSizeFactor {} -setnumber General.Verbosity "
          "0{} > /dev/null 2>&1",
          kGmshSeconds, f.string(), out.string(), hmax, hmin, factor, cm::bench::gmsh_unit_option(units));
      const double t0 = now();
      const int rc = std::system(cmd.c_str());
      g.seconds = now() - t0;
      if (rc == 0) {
        try {
          measure(cm::io::read_msh(cm::io::read_file_bytes(out.string()), out.string()), g);
          g.ok = true;
        } catch (const std::exception&) {
        }
      }
      return g;
    };
    // Our sizes give other counts than Gmsh's (sizes at short edges and
    // narrow faces): the last columns scale Gmsh's sizes until its count is
    // within 15% of ours, to compare speed and quality at a like count.
    Row matched;
    double factor = 1;
    if (have_gmsh)
      std::tie(theirs, matched, factor) = cm::bench::run_matched<Row>(
          run_gmsh, [](const Row& r) { return r.triangles; }, ours.triangles, 2);
    fmt::print("{:<36} {:>9} {:>8.3f} {:>6.3f} {:>6.3f} | ", f.filename().string(), ours.triangles, ours.seconds,
               ours.min_q, ours.mean_q);
    if (theirs.ok)
      fmt::print("{:>9} {:>8.3f} {:>6.3f} {:>6.3f} | {:>7.2f} | ", theirs.triangles, theirs.seconds, theirs.min_q,
                 theirs.mean_q, theirs.seconds / ours.seconds);
    else
      fmt::print("{:>33} | {:>7} | ",
                 !have_gmsh ? "no gmsh" : theirs.seconds >= kGmshSeconds ? "gmsh timed out" : "gmsh failed", "");
    if (matched.ok && std::abs(double(matched.triangles) / double(ours.triangles) - 1) <= cm::bench::kMatchedCount)
      fmt::print("{:>6.3f} {:>9} {:>8.3f} {:>6.3f} {:>6.3f} | {:>7.2f}\n", factor, matched.triangles, matched.seconds,
                 matched.min_q, matched.mean_q, matched.seconds / ours.seconds);
    else
      fmt::print("{:>40}\n", theirs.ok ? "no count within 15%" : "");
    std::fflush(stdout);  // a line per model as it finishes
  }
  fs::remove_all(tmp);
  return 0;
}
