// Quality optimization of existing meshes, side by side with Gmsh's
// optimizer (and mmg3d -optim when it is on PATH) on the same input.
//
// The input of each case is the mesh Gmsh makes of a model with its
// optimizer off:
//   gmsh -3 -nt 1 -setnumber Mesh.Optimize 0 -setnumber Mesh.MeshSizeFromCurvature 12
//        -setnumber Mesh.MeshSizeMax H MODEL -o in.msh
// or a mesh file given directly. Ours is `curvemesh optimize` without a
// size map (improve_quality). Gmsh cannot optimize a mesh it reads (its
// optimizer only runs on regions it meshed), so its side is the same command
// with Mesh.Optimize 1 and Mesh.OptimizeNetgen 1: the same tetrahedra
// (meshing is deterministic with one thread) and then its optimizers, whose
// own time is read from its log ("Done optimizing mesh (Wall w, CPU c)").
// A third row per model runs ours on the input with its interior vertices
// moved at random (kept positive) and some pushed almost flat.
// Times are CPU seconds of the optimization alone (the machine may be
// shared; wall time follows in the JSON records).
//
//   bench_optimize MODEL H [MODEL H ...]     e.g. t20_data.step 1.2 Zylkopf.stp 0.65
//   bench_optimize MESH.msh [...]            an existing mesh (no Gmsh row)
// Models are looked up in the shared models folder when not found as given.
// Prints a table, then one JSON record per row.
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/optimize/adapt.hpp"
#include "curvemesh/optimize/improve.hpp"
#include "curvemesh/quality/measures.hpp"
#include "shared_models.hpp"

namespace {

namespace fs = std::filesystem;
using cm::optimize::MeshSummary;

struct Case {
  fs::path file;
  double h = 0;  // > 0: a model, meshed by Gmsh at this MeshSizeMax
};

struct Row {
  std::string name, who;
  MeshSummary before, after;
  double cpu = 0, wall = 0;
  bool ok = false, valid = true;
  std::string note;
};

double cpu_now() { return static_cast<double>(std::clock()) / CLOCKS_PER_SEC; }

bool run(const std::string& cmd) { return std::system(cmd.c_str()) == 0; }

bool on_path(const std::string& program) { return run("command -v " + program + " > /dev/null 2>&1"); }

// Sums Gmsh's "Done optimizing mesh (Wall 0.67s, CPU 0.16s)" lines.
void gmsh_optimizer_times(const fs::path& log, double& wall, double& cpu) {
  static const std::regex re(R"(Done optimizing mesh \(Wall ([0-9.eE+-]+)s, CPU ([0-9.eE+-]+)s\))");
  std::ifstream in(log);
  std::string line;
  wall = cpu = 0;
  while (std::getline(in, line)) {
    std::smatch m;
    if (std::regex_search(line, m, re)) {
      wall += std::stod(m[1].str());
      cpu += std::stod(m[2].str());
    }
  }
}

std::string gmsh_command(const Case& c, const fs::path& out, bool optimize) {
  return fmt::format(
      "gmsh -3 -nt 1 -setnumber Mesh.Optimize {0} -setnumber Mesh.OptimizeNetgen {0} "
      "-setnumber Mesh.MeshSizeFromCurvature 12 -setnumber Mesh.MeshSizeMax {1} '{2}' -o '{3}' -format msh41 "
      "> '{3}.log' 2>&1",
      optimize ? 1 : 0, c.h, c.file.string(), out.string());
}

// Random interior moves that keep every tet positive, then some vertices
// pushed 99.9% of the way onto a face of their ball: the poor input a
// user's own smoothing or a morphing step leaves.
void perturb(cm::mesh::TetMesh& m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  std::vector<cm::TetId> ball;
  auto positive = [&] {
    for (cm::TetId t : ball) {
      const auto& v = m.tet2verts[t];
      if (cm::predicates::orient3d(m.coords[v[0]].data(), m.coords[v[1]].data(), m.coords[v[2]].data(),
                                   m.coords[v[3]].data()) <= 0)
        return false;
    }
    return true;
  };
  for (cm::VertId v = 0; v < m.num_verts(); ++v) {
    if (m.vert_class[v].dim != 3 || m.vert2tet[v] == cm::kNone) continue;
    cm::mesh::collect_ball(m, v, ball);
    double h = 0;
    for (cm::TetId t : ball)
      for (cm::VertId w : m.tet2verts[t]) h = std::max(h, (m.coords[w] - m.coords[v]).norm());
    const cm::Vec3 old = m.coords[v];
    m.coords[v] = old + 0.5 * h * cm::Vec3(u(rng), u(rng), u(rng));
    if (!positive()) m.coords[v] = old;
    if (rng() % 50 != 0) continue;  // about 2% of the vertices: flat tets
    const cm::TetId t = ball[rng() % ball.size()];
    cm::Vec3 f[3];
    int k = 0;
    for (cm::VertId w : m.tet2verts[t])
      if (w != v) f[k++] = m.coords[w];
    const cm::Vec3 n = (f[1] - f[0]).cross(f[2] - f[0]).normalized();
    const cm::Vec3 here = m.coords[v];
    m.coords[v] = here - 0.999 * n * n.dot(here - f[0]);
    if (!positive()) m.coords[v] = here;
  }
}

// The smallest angle of the domain at a boundary edge: the sum of the
// dihedral angles of the tets around it. No mesh with this boundary has a
// smaller largest-possible min dihedral, so it caps what any optimizer that
// keeps the boundary can reach.
double sharpest_wedge(const cm::mesh::TetMesh& m) {
  std::map<std::pair<cm::VertId, cm::VertId>, double> wedge;
  for (const auto& t : m.tris)
    for (const auto& e : cm::mesh::kTriEdges) wedge[std::minmax(t.verts[e[0]], t.verts[e[1]])] = 0;
  for (const auto& tv : m.tet2verts) {
    const auto angles = cm::quality::tet_dihedral_angles(m.coords[tv[0]], m.coords[tv[1]], m.coords[tv[2]],
                                                         m.coords[tv[3]]);
    for (int e = 0; e < 6; ++e) {
      const auto it = wedge.find(std::minmax(tv[cm::mesh::kTetEdges[e][0]], tv[cm::mesh::kTetEdges[e][1]]));
      if (it != wedge.end()) it->second += angles[static_cast<std::size_t>(e)];
    }
  }
  double lo = 360;
  for (const auto& [e, a] : wedge) lo = std::min(lo, a);
  return lo;
}

Row optimize_ours(const std::string& name, const std::string& who, cm::mesh::TetMesh m) {
  Row r{name, who, {}, {}, 0, 0, false, true, {}};
  r.before = cm::optimize::summarize_mesh(m);
  const double c0 = cpu_now();
  const cm::Timer wall;
  cm::optimize::ImproveOptions o;
  o.threshold = 0.6;  // as `curvemesh optimize`
  o.passes = 8;
  cm::optimize::improve_quality(m, o);
  r.wall = wall.seconds();
  r.cpu = cpu_now() - c0;
  r.after = cm::optimize::summarize_mesh(m);
  r.valid = cm::mesh::validate(m, cm::mesh::Level::kFull).valid();
  r.ok = true;
  return r;
}

void print_row(const Row& r, double reference_cpu) {
  if (!r.ok) {
    fmt::print("{:<28} {:<10} {}\n", r.name, r.who, r.note);
    return;
  }
  fmt::print("{:<28} {:<10} {:>8} {:>7.4f} {:>7.2f} | {:>8} {:>8.2f} {:>7.4f} {:>7.4f} {:>7.2f} {:>7.2f} {:>7}{}\n",
             r.name, r.who, r.before.tets, r.before.min_mean_ratio, r.before.min_dihedral, r.after.tets, r.cpu,
             r.after.min_mean_ratio, r.after.mean_mean_ratio, r.after.min_dihedral, r.after.max_dihedral,
             reference_cpu > 0 ? fmt::format("{:.2f}", r.cpu / reference_cpu) : "-", r.valid ? "" : "  INVALID");
}

nlohmann::json to_json(const Row& r) {
  auto s = [](const MeshSummary& m) {
    return nlohmann::json{{"tets", m.tets},
                          {"verts", m.verts},
                          {"min_mean_ratio", m.min_mean_ratio},
                          {"mean_mean_ratio", m.mean_mean_ratio},
                          {"min_dihedral", m.min_dihedral},
                          {"max_dihedral", m.max_dihedral},
                          {"volume", m.volume}};
  };
  return {{"case", r.name}, {"optimizer", r.who}, {"ok", r.ok},          {"valid", r.valid},
          {"cpu_s", r.cpu}, {"wall_s", r.wall},   {"before", s(r.before)}, {"after", s(r.after)},
          {"note", r.note}};
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<Case> cases;
  for (int i = 1; i < argc; ++i) {
    fs::path f = argv[i];
    if (!fs::exists(f)) f = cm::bench::models_dir() / argv[i];
    Case c{f, 0};
    const std::string ext = f.extension().string();
    const bool is_mesh = ext == ".msh" || ext == ".mesh" || ext == ".meshb";
    if (!is_mesh && i + 1 < argc) c.h = std::atof(argv[++i]);
    if (!is_mesh && !(c.h > 0)) {
      fmt::print(stderr, "{}: a model needs a size H after it\n", argv[i]);
      return 2;
    }
    cases.push_back(c);
  }
  if (cases.empty()) {
    cases = {{cm::bench::models_dir() / "t20_data.step", 1.2}, {cm::bench::models_dir() / "Zylkopf.stp", 0.65}};
  }
  const bool have_gmsh = on_path("gmsh");
  const bool have_mmg = on_path("mmg3d_O3");
  const fs::path tmp = fs::temp_directory_path() / fmt::format("curvemesh_bench_optimize_{}", getpid());
  fs::create_directories(tmp);
  fmt::print("{:<28} {:<10} {:>8} {:>7} {:>7} | {:>8} {:>8} {:>7} {:>7} {:>7} {:>7} {:>7}\n", "case", "optimizer",
             "tets in", "minq", "mindih", "tets out", "cpu s", "minq", "meanq", "mindih", "maxdih", "t/ours");
  std::vector<Row> rows;
  for (const Case& c : cases) {
    const std::string name = c.file.filename().string() + (c.h > 0 ? fmt::format(" H={}", c.h) : "");
    fs::path input = c.file;
    if (c.h > 0) {
      if (!have_gmsh) {
        fmt::print("{:<28} skipped: gmsh is not on PATH to mesh the model\n", name);
        continue;
      }
      input = tmp / "in.msh";
      if (!run(gmsh_command(c, input, false))) {
        fmt::print("{:<28} gmsh failed to mesh it (see {}.log)\n", name, input.string());
        continue;
      }
    }
    cm::mesh::TetMesh m;
    try {
      m = cm::io::read_mesh(input.string());
    } catch (const std::exception& e) {
      fmt::print("{:<28} cannot read the input: {}\n", name, e.what());
      continue;
    }
    fmt::print("{:<28} sharpest boundary wedge {:.2f} deg: the cap on min dihedral with this boundary\n", name,
               sharpest_wedge(m));
    const Row ours = optimize_ours(name, "curvemesh", m);
    print_row(ours, 0);
    rows.push_back(ours);

    if (c.h > 0) {
      Row g{name, "gmsh", ours.before, {}, 0, 0, false, true, {}};
      const fs::path out = tmp / "gmsh_opt.msh";
      // A Gmsh built without Netgen logs an error for OptimizeNetgen and
      // exits non-zero, yet writes the mesh its own optimizer made.
      run(gmsh_command(c, out, true));
      if (fs::exists(out) && fs::file_size(out) > 0) {
        gmsh_optimizer_times(fs::path(out.string() + ".log"), g.wall, g.cpu);
        try {
          const auto gm = cm::io::read_mesh(out.string());
          g.after = cm::optimize::summarize_mesh(gm);
          g.valid = cm::mesh::validate(gm, cm::mesh::Level::kTopology).valid();
          g.ok = true;
        } catch (const std::exception& e) {
          g.note = fmt::format("cannot read its output: {}", e.what());
        }
      } else {
        g.note = "gmsh failed";
      }
      print_row(g, ours.cpu);
      rows.push_back(g);
    }
    if (have_mmg) {
      Row r{name, "mmg3d", ours.before, {}, 0, 0, false, true, {}};
      const fs::path in_mesh = tmp / "mmg_in.mesh", out_mesh = tmp / "mmg_out.mesh";
      cm::io::write_mesh(m, in_mesh.string());
      const cm::Timer wall;
      const bool done = run(fmt::format("mmg3d_O3 -optim -nofem '{}' -out '{}' > '{}.log' 2>&1", in_mesh.string(),
                                        out_mesh.string(), out_mesh.string()));
      // A child's CPU time is not in std::clock: its wall time stands in
      // (it includes mmg's reading and writing).
      r.wall = r.cpu = wall.seconds();
      if (done) {
        try {
          const auto mm = cm::io::read_mesh(out_mesh.string());
          r.after = cm::optimize::summarize_mesh(mm);
          r.valid = cm::mesh::validate(mm, cm::mesh::Level::kTopology).valid();
          r.ok = true;
        } catch (const std::exception& e) {
          r.note = fmt::format("cannot read its output: {}", e.what());
        }
      } else {
        r.note = "mmg3d_O3 failed";
      }
      print_row(r, ours.cpu);
      rows.push_back(r);
    }
    cm::mesh::TetMesh p = m;
    perturb(p, 12345);
    const Row perturbed = optimize_ours(name + " perturbed", "curvemesh", std::move(p));
    print_row(perturbed, 0);
    rows.push_back(perturbed);
  }
  for (const Row& r : rows) fmt::print("{}\n", to_json(r).dump());
  fs::remove_all(tmp);
  return 0;
}
