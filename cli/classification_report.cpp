#include "classification_report.hpp"

#include <fmt/format.h>

namespace cm::cli {

nlohmann::json classification_json(const generate::ModelClassification& c) {
  nlohmann::json faces = nlohmann::json::array(), regions = nlohmann::json::array();
  for (const auto& f : c.face_map)
    faces.push_back({{"input", f.input}, {"model", f.model}, {"triangles", f.count}, {"elsewhere", f.others}});
  for (const auto& r : c.region_map) regions.push_back({{"input", r.input}, {"model", r.model}, {"tets", r.count}});
  return {{"boundary_triangles", c.boundary_triangles},
          {"input_faces", c.input_faces},
          {"input_faces_whole", c.input_faces_whole},
          {"triangles_searched", c.triangles_searched},
          {"triangles_dropped", c.triangles_dropped},
          {"triangles_flipped", c.triangles_flipped},
          {"vertices_on_model_vertices", c.vertices_on_model_vertices},
          {"vertices_on_model_edges", c.vertices_on_model_edges},
          {"vertices_on_model_faces", c.vertices_on_model_faces},
          {"interior_vertices", c.interior_vertices},
          {"mesh_edges_on_model_edges", c.mesh_edges_on_model_edges},
          {"changed", {{"vertices", c.vertices_changed}, {"triangles", c.triangles_changed}, {"edges", c.edges_changed},
                       {"tets", c.tets_changed}}},
          {"max_distance", c.max_distance},
          {"max_distance_over_tolerance", c.max_relative_distance},
          {"face_map", faces},
          {"region_map", regions},
          {"problems", c.problems},
          {"num_problems", c.num_problems},
          {"seconds", c.seconds}};
}

std::string render_classification(const generate::ModelClassification& c) {
  std::string s = fmt::format(
      "classified on the model: {} boundary triangles from {} input faces, {} of them whole on one model face{}{}; "
      "boundary vertices: {} on model vertices, {} on model edges, {} on model faces; {} mesh edges on model edges\n"
      "  changed: {} vertices, {} triangles ({} reversed), {} mesh edges, {} tets; farthest vertex {:.3g} from its "
      "entity ({:.3g} of its tolerance); {:.2f} s\n",
      c.boundary_triangles, c.input_faces, c.input_faces_whole,
      c.triangles_searched ? fmt::format(", {} triangles placed one by one", c.triangles_searched) : "",
      c.triangles_dropped ? fmt::format(", {} inside the model dropped", c.triangles_dropped) : "",
      c.vertices_on_model_vertices, c.vertices_on_model_edges, c.vertices_on_model_faces, c.mesh_edges_on_model_edges,
      c.vertices_changed, c.triangles_changed, c.triangles_flipped, c.edges_changed, c.tets_changed, c.max_distance,
      c.max_relative_distance, c.seconds);
  for (const auto& p : c.problems) s += "  warning: " + p + "\n";
  if (c.num_problems > c.problems.size()) s += fmt::format("  ... {} more warnings\n", c.num_problems - c.problems.size());
  return s;
}

}  // namespace cm::cli
