// Quality optimization of existing meshes, side by side with Gmsh's
// optimizer (and mmg3d -optim when it is on PATH) on the same input; then
// adaptation of a box to analytic size and metric fields (and mmg3d
// adapting to the same field given as a .sol, when it is on PATH).
//
// The input of each case is the mesh Gmsh makes of a model with its
// optimizer off:
//   gmsh -3 -nt 1 -setnumber Mesh.Optimize 0 -setnumber Mesh.MeshSizeFromCurvature 12
//        -setnumber Mesh.MeshSizeMax H MODEL -o in.msh
// or a mesh file given directly. Ours is `curvemesh optimize` without a
// size map (improve_quality). Gmsh's command line cannot optimize a mesh it
// reads (its optimizer only runs on regions it meshed), so its side is the
// same command with Mesh.Optimize 1 and Mesh.OptimizeNetgen 1: the same tetrahedra
// (meshing is deterministic with one thread) and then its optimizers, whose
// own time is read from its log ("Done optimizing mesh (Wall w, CPU c)").
// Another row runs ours with the model (`curvemesh optimize --model`): the
// Gmsh mesh classified on it (generate::classify_on_model, its time in the
// JSON record), then boundary vertices moved on their model face or edge.
// Gmsh is told the model's length unit so that its mesh and H are in it.
// A last pair of rows per model runs ours, and Gmsh's optimizer through its
// Python API when python3-gmsh is installed, on the input with its interior
// vertices moved at random (kept positive) and some pushed almost flat.
// Times are CPU seconds of the optimization alone (the machine may be
// shared; wall time follows in the JSON records).
//
//   bench_optimize MODEL H [MODEL H ...]     e.g. t20_data.step 1.2 Zylkopf.stp 0.65
//   bench_optimize MESH.msh [...]            an existing mesh (no Gmsh row)
//   bench_optimize --adapt-only              only the analytic adaptation cases
// Models are looked up in the shared models folder when not found as given.
// Prints a table, then one JSON record per row.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "curvemesh/core/predicates.hpp"
#include "curvemesh/core/timer.hpp"
#include "curvemesh/generate/classify_on_model.hpp"
#include "curvemesh/geom_occ/load.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/mesh_io.hpp"
#include "curvemesh/mesh/adjacency.hpp"
#include "curvemesh/mesh/structured.hpp"
#include "curvemesh/mesh/validate.hpp"
#include "curvemesh/optimize/adapt.hpp"
#include "curvemesh/optimize/boundary_limit.hpp"
#include "curvemesh/optimize/improve.hpp"
#include "curvemesh/quality/measures.hpp"
#include "curvemesh/size/expression.hpp"
#include "shared_models.hpp"

namespace {

namespace fs = std::filesystem;
using cm::optimize::MeshSummary;

struct Case {
  fs::path file;
  double h = 0;  // > 0: a model, meshed by Gmsh at this MeshSizeMax
  std::string units;  // the model's, once loaded
};

struct Row {
  std::string name, who;
  MeshSummary before, after;
  cm::optimize::BoundaryLimit limit;  // of the output
  double cpu = 0, wall = 0;
  bool ok = false, valid = true;
  std::string note;
  double classify_s = 0;  // classification on the model (wall), before the optimization
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
      "-setnumber Mesh.MeshSizeFromCurvature 12 -setnumber Mesh.MeshSizeMax {1}{4} '{2}' -o '{3}' -format msh41 "
      "> '{3}.log' 2>&1",
      optimize ? 1 : 0, c.h, c.file.string(), out.string(), cm::bench::gmsh_unit_option(c.units));
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

// Gmsh's optimizer on a mesh it reads, through its Python API (Debian's
// python3-gmsh, for the system interpreter): gmsh.model.mesh.optimize with
// force set runs on discrete volumes too, which the command line cannot (its
// optimizer only runs after meshing). Netgen's optimizer follows when this
// Gmsh has it (Debian's does not). Its log has the same "Done optimizing
// mesh" lines. Returns the interpreter, or "" when none has the module.
std::string gmsh_python() {
  for (const char* python : {"/usr/bin/python3", "python3"})
    if (run(fmt::format("{} -c 'import gmsh' > /dev/null 2>&1", python))) return python;
  return {};
}

bool gmsh_optimize_mesh(const std::string& python, const fs::path& in, const fs::path& out, const fs::path& log) {
  const fs::path script = out.parent_path() / "gmsh_optimize.py";
  std::ofstream(script) << "import sys, gmsh\n"
                           "gmsh.initialize()\n"
                           "gmsh.option.setNumber('General.Terminal', 1)\n"
                           "gmsh.option.setNumber('Mesh.MshFileVersion', 4.1)\n"
                           "gmsh.open(sys.argv[1])\n"
                           "gmsh.model.mesh.optimize('', force=True)\n"
                           "try:\n"
                           "    gmsh.model.mesh.optimize('Netgen', force=True)\n"
                           "except Exception:\n"
                           "    pass\n"
                           "gmsh.write(sys.argv[2])\n"
                           "gmsh.finalize()\n";
  return run(fmt::format("{} '{}' '{}' '{}' > '{}' 2>&1", python, script.string(), in.string(), out.string(),
                         log.string()));
}

// Reads what another optimizer wrote into r (its quality, what holds its
// worst tets, validity).
void read_result(const fs::path& out, Row& r) {
  try {
    const auto mm = cm::io::read_mesh(out.string());
    r.after = cm::optimize::summarize_mesh(mm);
    r.limit = cm::optimize::classify_boundary_limit(mm);
    r.valid = cm::mesh::validate(mm, cm::mesh::Level::kTopology).valid();
    r.ok = true;
  } catch (const std::exception& e) {
    r.note = fmt::format("cannot read its output: {}", e.what());
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

Row optimize_ours(const std::string& name, const std::string& who, cm::mesh::TetMesh m,
                  const cm::geom::Model* model = nullptr) {
  Row r{name, who, {}, {}, {}, 0, 0, false, true, {}};
  r.before = cm::optimize::summarize_mesh(m);
  const double c0 = cpu_now();
  const cm::Timer wall;
  cm::optimize::ImproveOptions o;
  o.threshold = 0.6;  // as `curvemesh optimize`
  o.passes = 8;
  o.model = model;
  cm::optimize::improve_quality(m, o);
  r.wall = wall.seconds();
  r.cpu = cpu_now() - c0;
  r.after = cm::optimize::summarize_mesh(m);
  r.limit = cm::optimize::classify_boundary_limit(m);
  r.valid = cm::mesh::validate(m, cm::mesh::Level::kFull).valid();
  r.ok = true;
  return r;
}

void print_row(const Row& r, double reference_cpu) {
  if (!r.ok) {
    fmt::print("{:<28} {:<10} {}\n", r.name, r.who, r.note);
    return;
  }
  const auto& l = r.limit;
  fmt::print(
      "{:<28} {:<10} {:>8} {:>7.4f} {:>7.2f} | {:>8} {:>8.2f} {:>7.4f} {:>7.4f} {:>7.2f} {:>7.2f} {:>7} | {:>5} {:>7} "
      "{:>7} | {:>5} {:>7.4f} {:>7.2f}{}\n",
      r.name, r.who, r.before.tets, r.before.min_mean_ratio, r.before.min_dihedral, r.after.tets, r.cpu,
      r.after.min_mean_ratio, r.after.mean_mean_ratio, r.after.min_dihedral, r.after.max_dihedral,
      reference_cpu > 0 ? fmt::format("{:.2f}", r.cpu / reference_cpu) : "-", l.pinned,
      l.pinned ? fmt::format("{:.2f}", l.pinned_min_dihedral) : "-",
      l.pinned ? fmt::format("{:.2f}", l.pinned_min_cap) : "-", l.free_below, l.free_min_mean_ratio,
      l.free_min_dihedral, r.valid ? "" : "  INVALID");
}

// Where the worst tets of a row are and what holds them.
void print_worst(const Row& r, std::size_t count) {
  for (std::size_t i = 0; i < std::min(count, r.limit.worst.size()); ++i) {
    const auto& w = r.limit.worst[i];
    fmt::print("    {:6.2f} deg  q {:.4f}  {:<18} cap {:6.2f}{}  {} boundary verts, {} boundary faces, at ({:.4g}, "
               "{:.4g}, {:.4g})\n",
               w.dihedral, w.mean_ratio, cm::optimize::to_string(w.why), w.cap,
               w.price < 1 ? fmt::format("  q at {:g} deg {:.4f}", r.limit.target, w.price) : "", w.boundary_verts,
               w.boundary_faces, w.centroid.x(), w.centroid.y(), w.centroid.z());
  }
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
  const auto& l = r.limit;
  const nlohmann::json limit = {{"target_deg", l.target},
                                {"pinned", l.pinned},
                                {"pinned_by_two_faces", l.by_two_faces},
                                                      {"pinned_by_wedge", l.by_wedge},
                                {"pinned_min_dihedral", l.pinned_min_dihedral},
                                {"pinned_min_mean_ratio", l.pinned_min_mean_ratio},
                                {"pinned_min_cap", l.pinned_min_cap},
                                {"free_below", l.free_below},
                                {"held_by_thin_face", l.held_by_thin_face},
                                {"held_min_price", l.min_price},
                                {"free_min_dihedral", l.free_min_dihedral},
                                {"free_min_mean_ratio", l.free_min_mean_ratio}};
  return {{"case", r.name},       {"optimizer", r.who},     {"ok", r.ok},       {"valid", r.valid},
          {"cpu_s", r.cpu},       {"wall_s", r.wall},       {"before", s(r.before)}, {"after", s(r.after)},
          {"boundary_limit", limit}, {"note", r.note}, {"classify_s", r.classify_s}};
}

// Adaptation to analytic fields on the unit box: a shock-like isotropic
// size across x = 0.5, and a metric that is fine across the same plane and
// coarse along it.
class AxisSizes final : public cm::size::SizeField {
 public:
  /// Sizes along the columns of `frame` (orthonormal; the coordinate axes
  /// by default).
  explicit AxisSizes(std::array<std::shared_ptr<const cm::size::SizeField>, 3> axes,
                     const cm::Mat3& frame = cm::Mat3::Identity())
      : axes_(std::move(axes)), frame_(frame) {}
  double size(const cm::Vec3& x, const cm::size::SizeHint& = {}) const override {
    return std::min({axes_[0]->size(x), axes_[1]->size(x), axes_[2]->size(x)});
  }
  cm::size::Metric metric(const cm::Vec3& x, const cm::size::SizeHint& = {}) const override {
    cm::size::Metric m = cm::size::Metric::Zero();
    for (int k = 0; k < 3; ++k) m(k, k) = 1 / std::pow(axes_[static_cast<std::size_t>(k)]->size(x), 2);
    return frame_ * m * frame_.transpose();
  }
  bool anisotropic() const override { return true; }

 private:
  std::array<std::shared_ptr<const cm::size::SizeField>, 3> axes_;
  cm::Mat3 frame_;
};

struct AdaptCase {
  std::string name;
  std::shared_ptr<const cm::size::SizeField> field;
};

// mmg3d adapting the same box to the same field: given it at the box's
// vertices as a .sol (no gradation, as ours), its output judged by the
// analytic field at its own vertices, as ours is.
void run_mmg_adaptation(const AdaptCase& c, int cells, const std::string& mmg, const fs::path& tmp) {
  const auto box = cm::mesh::make_box_mesh({cells, cells, cells}, cm::Vec3(0, 0, 0), cm::Vec3(1, 1, 1), true);
  const auto field = cm::optimize::metric_field_from_size_field(box, *c.field);
  const fs::path in_mesh = tmp / "adapt_in.mesh", in_sol = tmp / "adapt_in.sol", out_mesh = tmp / "adapt_out.mesh";
  cm::io::write_mesh(box, in_mesh.string());
  cm::io::SolField sol;
  sol.type = field.anisotropic() ? cm::io::SolField::Type::kTensor : cm::io::SolField::Type::kScalar;
  sol.values = cm::optimize::metric_field_values(field);
  cm::io::write_sol(sol, in_sol.string(), false);
  const cm::Timer wall;
  const bool done = run(fmt::format("{} -in '{}' -sol '{}' -out '{}' -hgrad -1 > '{}.log' 2>&1", mmg, in_mesh.string(),
                                    in_sol.string(), out_mesh.string(), out_mesh.string()));
  const double wall_s = wall.seconds();
  cm::mesh::TetMesh out;
  try {
    if (!done) throw std::runtime_error(fmt::format("{} failed (see {}.log)", mmg, out_mesh.string()));
    out = cm::io::read_mesh(out_mesh.string());
    cm::mesh::build_adjacency(out);
  } catch (const std::exception& e) {
    fmt::print("{:<34} mmg3d: {}\n", c.name, e.what());
    return;
  }
  const auto judged = cm::optimize::metric_field_from_size_field(out, *c.field);
  const auto after = cm::optimize::summarize_mesh(out, &judged);
  const auto l = cm::optimize::measure_lengths(out, judged);
  // A child's CPU time is not in std::clock: its wall time (reading and
  // writing included) stands in.
  fmt::print("{:<34} {:>7} -> {:>7} tets  {:>7.2f} s  in [0.7,1.4]          {:5.1f}%  metric q min {:.4f} mean "
             "{:.4f}  min dih {:5.2f}  ({}, wall)\n",
             "  " + mmg, box.num_tets(), after.tets, wall_s, l.percent_in_range(), after.min_metric_quality,
             after.mean_metric_quality, after.min_dihedral, mmg);
  fmt::print("{}\n", nlohmann::json{{"case", c.name},
                                    {"optimizer", mmg + " adapt"},
                                    {"wall_s", wall_s},
                                    {"tets_after", after.tets},
                                    {"percent_in_range_after", l.percent_in_range()},
                                    {"too_short_after", l.too_short},
                                    {"too_long_after", l.too_long},
                                    {"metric_quality_min", after.min_metric_quality},
                                    {"metric_quality_mean", after.mean_metric_quality},
                                    {"min_dihedral", after.min_dihedral}}
                        .dump());
}

void run_adaptation(const AdaptCase& c, int cells, const std::string& mmg, const fs::path& tmp) {
  auto m = cm::mesh::make_box_mesh({cells, cells, cells}, cm::Vec3(0, 0, 0), cm::Vec3(1, 1, 1), true);
  auto field = cm::optimize::metric_field_from_size_field(m, *c.field);
  const auto before = cm::optimize::summarize_mesh(m, &field);
  cm::optimize::AdaptOptions o;
  o.sizes = c.field.get();
  // As `curvemesh optimize --move-flat-boundary` runs it: the box's faces
  // are flat, and an anisotropic metric is worked on up to 0.9.
  o.flat_boundary = true;
  if (c.field->anisotropic()) o.threshold = 0.9;
  const double c0 = cpu_now();
  const cm::Timer wall;
  const auto st = cm::optimize::adapt_to_metric(m, field, o);
  const double cpu = cpu_now() - c0, wall_s = wall.seconds();
  const auto after = cm::optimize::summarize_mesh(m, &field);
  const bool valid = cm::mesh::validate(m, cm::mesh::Level::kFull).valid();
  fmt::print("{:<34} {:>7} -> {:>7} tets  {:>7.2f} s  in [0.7,1.4] {:5.1f}% -> {:5.1f}%  metric q min {:.4f} mean "
             "{:.4f}  min dih {:5.2f}  (split {:.2f} s, collapse {:.2f} s, swap {:.2f} s, reloc {:.2f} s){}\n",
             c.name, before.tets, after.tets, cpu, st.lengths_before.percent_in_range(),
             st.lengths_after.percent_in_range(), after.min_metric_quality, after.mean_metric_quality,
             after.min_dihedral, st.split_seconds, st.collapse_seconds, st.swap_seconds, st.relocation_seconds,
             valid ? "" : "  INVALID");
  const auto& l = st.lengths_after;
  fmt::print("{:<34} lengths min {:.3f} mean {:.3f} max {:.3f}, short {} long {} of {}; per 0.25: {}\n", "", l.min,
             l.mean, l.max, l.too_short, l.too_long, l.edges, fmt::join(l.histogram, " "));
  fmt::print("{}\n", nlohmann::json{{"case", c.name},
                                    {"optimizer", "curvemesh adapt"},
                                    {"valid", valid},
                                    {"cpu_s", cpu},
                                    {"wall_s", wall_s},
                                    {"tets_before", before.tets},
                                    {"tets_after", after.tets},
                                    {"percent_in_range_before", st.lengths_before.percent_in_range()},
                                    {"percent_in_range_after", st.lengths_after.percent_in_range()},
                                    {"too_short_after", st.lengths_after.too_short},
                                    {"too_long_after", st.lengths_after.too_long},
                                    {"threshold", o.threshold},
                                    {"metric_quality_min", after.min_metric_quality},
                                    {"metric_quality_mean", after.mean_metric_quality},
                                    {"min_dihedral", after.min_dihedral},
                                    {"splits", st.splits},
                                    {"collapses", st.collapses},
                                    {"split_s", st.split_seconds},
                                    {"collapse_s", st.collapse_seconds},
                                    {"swap_s", st.swap_seconds},
                                    {"relocation_s", st.relocation_seconds}}
                        .dump());
  if (!mmg.empty()) run_mmg_adaptation(c, cells, mmg, tmp);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<Case> cases;
  bool adapt_only = false;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--adapt-only") {
      adapt_only = true;
      continue;
    }
    fs::path f = argv[i];
    if (!fs::exists(f)) f = cm::bench::models_dir() / argv[i];
    Case c{f, 0, {}};
    const std::string ext = f.extension().string();
    const bool is_mesh = ext == ".msh" || ext == ".mesh" || ext == ".meshb";
    if (!is_mesh && i + 1 < argc) c.h = std::atof(argv[++i]);
    if (!is_mesh && !(c.h > 0)) {
      fmt::print(stderr, "{}: a model needs a size H after it\n", argv[i]);
      return 2;
    }
    cases.push_back(c);
  }
  if (cases.empty() && !adapt_only) {
    cases = {{cm::bench::models_dir() / "t20_data.step", 1.2, {}}, {cm::bench::models_dir() / "Zylkopf.stp", 0.65, {}}};
  }
  // How many of the worst tets left under 10 degrees to list per row.
  const std::size_t worst_listed = std::getenv("CM_BENCH_WORST") ? std::stoul(std::getenv("CM_BENCH_WORST")) : 3;
  const bool have_gmsh = on_path("gmsh");
  // MMG installs its 3D remesher as mmg3d_O3 (its build's name) or mmg3d.
  const std::string mmg = on_path("mmg3d_O3") ? "mmg3d_O3" : on_path("mmg3d") ? "mmg3d" : "";
  const bool have_mmg = !mmg.empty();
  const std::string python = gmsh_python();
  const bool have_gmsh_python = !python.empty();
  const fs::path tmp = fs::temp_directory_path() / fmt::format("curvemesh_bench_optimize_{}", getpid());
  fs::create_directories(tmp);
  // After the output's quality: the tets under 10 degrees the boundary pins
  // (count, their worst angle, the best the boundary allows there), then
  // the free ones under 10 degrees and the worst mean ratio and angle of
  // all free tets (boundary_limit.hpp).
  fmt::print("{:<28} {:<10} {:>8} {:>7} {:>7} | {:>8} {:>8} {:>7} {:>7} {:>7} {:>7} {:>7} | {:>5} {:>7} {:>7} | {:>5} "
             "{:>7} {:>7}\n",
             "case", "optimizer", "tets in", "minq", "mindih", "tets out", "cpu s", "minq", "meanq", "mindih",
             "maxdih", "t/ours", "pin", "pin dih", "pin cap", "free<", "freeq", "freedih");
  std::vector<Row> rows;
  for (Case& c : cases) {
    const std::string name = c.file.filename().string() + (c.h > 0 ? fmt::format(" H={}", c.h) : "");
    fs::path input = c.file;
    std::unique_ptr<cm::geom::Model> model;
    if (c.h > 0) {
      try {
        model = cm::geom_occ::load_model(c.file.string());
        c.units = model->units();
      } catch (const std::exception& e) {
        fmt::print("{:<28} cannot load the model: {}\n", name, e.what());
        continue;
      }
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
    print_worst(ours, worst_listed);
    rows.push_back(ours);

    if (model) {
      cm::mesh::TetMesh on_model = m;
      try {
        const auto cls = cm::generate::classify_on_model(on_model, *model, {input.string()});
        Row r = optimize_ours(name, "cm+model", std::move(on_model), model.get());
        r.classify_s = cls.seconds;
        if (cls.num_problems) r.note = fmt::format("{} classification warnings", cls.num_problems);
        print_row(r, ours.cpu);
        fmt::print("    classified on the model in {:.3f} s: {} vertices, {} triangles, {} tets reclassified{}\n",
                   cls.seconds, cls.vertices_changed, cls.triangles_changed, cls.tets_changed,
                   cls.problems.empty() ? "" : "; first warning: " + cls.problems.front());
        print_worst(r, worst_listed);
        rows.push_back(r);
      } catch (const std::exception& e) {
        fmt::print("{:<28} {:<10} cannot classify it on the model: {}\n", name, "cm+model", e.what());
      }
    }
    if (c.h > 0) {
      Row g{name, "gmsh", ours.before, {}, {}, 0, 0, false, true, {}};
      const fs::path out = tmp / "gmsh_opt.msh";
      // A Gmsh built without Netgen logs an error for OptimizeNetgen and
      // exits non-zero, yet writes the mesh its own optimizer made.
      run(gmsh_command(c, out, true));
      if (fs::exists(out) && fs::file_size(out) > 0) {
        gmsh_optimizer_times(fs::path(out.string() + ".log"), g.wall, g.cpu);
        read_result(out, g);
      } else {
        g.note = "gmsh failed";
      }
      print_row(g, ours.cpu);
      print_worst(g, worst_listed);
      rows.push_back(g);
    }
    if (have_mmg) {
      Row r{name, "mmg3d", ours.before, {}, {}, 0, 0, false, true, {}};
      const fs::path in_mesh = tmp / "mmg_in.mesh", out_mesh = tmp / "mmg_out.mesh";
      cm::io::write_mesh(m, in_mesh.string());
      const cm::Timer wall;
      const bool done = run(fmt::format("{} -optim -nofem '{}' -out '{}' > '{}.log' 2>&1", mmg, in_mesh.string(),
                                        out_mesh.string(), out_mesh.string()));
      // A child's CPU time is not in std::clock: its wall time stands in
      // (it includes mmg's reading and writing).
      r.wall = r.cpu = wall.seconds();
      if (done) {
        read_result(out_mesh, r);
      } else {
        r.note = mmg + " failed";
      }
      print_row(r, ours.cpu);
      rows.push_back(r);
    }
    cm::mesh::TetMesh p = m;
    perturb(p, 12345);
    const fs::path perturbed_in = tmp / "perturbed.msh";
    if (have_gmsh_python) cm::io::write_mesh(p, perturbed_in.string());
    const Row perturbed = optimize_ours(name + " perturbed", "curvemesh", std::move(p));
    print_row(perturbed, 0);
    print_worst(perturbed, worst_listed);
    rows.push_back(perturbed);
    if (have_gmsh_python) {
      Row g{name + " perturbed", "gmsh", perturbed.before, {}, {}, 0, 0, false, true, {}};
      const fs::path out = tmp / "perturbed_gmsh.msh", log = tmp / "perturbed_gmsh.log";
      if (gmsh_optimize_mesh(python, perturbed_in, out, log)) {
        gmsh_optimizer_times(log, g.wall, g.cpu);
        read_result(out, g);
      } else {
        g.note = fmt::format("gmsh's Python API failed (see {})", log.string());
      }
      print_row(g, perturbed.cpu);
      print_worst(g, worst_listed);
      rows.push_back(g);
    }
  }
  for (const Row& r : rows) fmt::print("{}\n", to_json(r).dump());
  if (!std::getenv("CM_BENCH_NO_ADAPT")) {
    using cm::size::make_expression_field;
    fmt::print("\nadaptation of a 10^3 Kuhn box to analytic fields (new vertices take the field's value; boundary "
               "vertices move and go within the box's flat faces):\n");
    run_adaptation({"shock h=0.02+0.2|x-0.5|", make_expression_field("0.02 + 0.2*abs(x - 0.5)")}, 10, mmg, tmp);
    run_adaptation({"aniso hx=0.01+0.2|x-0.5|, 0.1, 0.1",
                    std::make_shared<AxisSizes>(std::array<std::shared_ptr<const cm::size::SizeField>, 3>{
                        make_expression_field("0.01 + 0.2*abs(x - 0.5)"), make_expression_field("0.1"),
                        make_expression_field("0.1")})},
                   10, mmg, tmp);
    // The same across the diagonal plane x + y = 1: the metric's axes are
    // not the mesh's, nor the box's.
    cm::Mat3 diagonal;
    diagonal << 0.70710678118654752, -0.70710678118654752, 0, 0.70710678118654752, 0.70710678118654752, 0, 0, 0, 1;
    run_adaptation({"aniso rotated, fine across x+y=1",
                    std::make_shared<AxisSizes>(
                        std::array<std::shared_ptr<const cm::size::SizeField>, 3>{
                            make_expression_field("0.01 + 0.2*abs(x + y - 1)*0.70710678118654752"),
                            make_expression_field("0.1"), make_expression_field("0.1")},
                        diagonal)},
                   10, mmg, tmp);
  }
  fs::remove_all(tmp);
  return 0;
}
