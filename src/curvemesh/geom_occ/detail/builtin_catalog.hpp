#pragma once
// Internal to geom_occ: the built-in models' names, parameters and defaults.
// The program lists them in its help without loading the plugin that builds
// them (plugins/builtin_shapes.cpp), which parses specs against this table.
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

namespace cm::geom_occ::detail {

struct Builtin {
  std::string_view name;
  std::string_view description;
  std::vector<std::pair<std::string_view, double>> defaults;
};

inline const std::vector<Builtin>& builtins() {
  static const std::vector<Builtin> kBuiltins = {
      {"box", "box [0,dx] x [0,dy] x [0,dz]", {{"dx", 1}, {"dy", 1}, {"dz", 1}}},
      {"sphere", "sphere of radius r centred at the origin", {{"r", 1}}},
      {"cylinder", "cylinder of radius r and height h on the z axis from z = 0",
       {{"r", 1}, {"h", 2}}},
      {"torus", "torus about the z axis: major radius R > minor radius r",
       {{"R", 2}, {"r", 0.5}}},
      {"cone", "truncated cone on the z axis: radius r1 at z = 0, r2 at z = h (one may be 0)",
       {{"r1", 1}, {"r2", 0.5}, {"h", 2}}},
      {"part",
       "mechanical part: a 60x40x20 block (times scale) with filleted vertical edges, two "
       "through holes and a freeform B-spline top face",
       {{"scale", 1}}},
      {"blocks",
       "two regions sharing the face x = dx1: boxes [0,dx1] x [0,dy] x [0,dz] and "
       "[dx1-o,dx1+dx2] x [0,dy] x [0,dz] (o: an overlap, as of parts that interpenetrate by a hair)",
       {{"dx1", 1}, {"dx2", 1}, {"dy", 1}, {"dz", 1}, {"o", 0}}},
      {"inclusion",
       "two regions: a sphere of radius r inside the cube [-s/2,s/2]^3, and the rest of the cube",
       {{"s", 2}, {"r", 0.5}}},
      {"thinwall",
       "thin-walled tube on the z axis from z = 0 to h: outer radius r, wall thickness t < r",
       {{"r", 1}, {"t", 0.02}, {"h", 2}}},
      {"holes",
       "plate [0,s] x [0,s] x [0,h] with an n x n grid of through holes of radius r, one "
       "centred in each cell (2r < s/n)",
       {{"n", 6}, {"s", 1}, {"h", 0.2}, {"r", 0.05}}},
      {"tangent",
       "near-tangent faces: the box [0,2] x [0,1] x [0,1] fused with a cylinder of radius r "
       "along x (x in [0.5,1.5], y = 0.5) sunk d into its top face; the surfaces meet at "
       "about sqrt(2d/r) radians",
       {{"r", 0.3}, {"d", 0.001}}},
      {"smalledges",
       "small edges: the cube [0,s]^3 with a chamfer of width e on one top edge, a step of "
       "height e across a third of its top and a notch cube of side e at a bottom corner",
       {{"s", 1}, {"e", 0.001}}},
  };
  return kBuiltins;
}

/// The built-ins with parameters and defaults (load.hpp's builtin_help()).
inline std::string builtin_help_text() {
  std::string text;
  for (const Builtin& b : builtins()) {
    std::string params;
    for (const auto& [key, value] : b.defaults)
      params += fmt::format("{}{}={:g}", params.empty() ? "" : ",", key, value);
    text += fmt::format("  builtin:{}:{}\n      {}\n", b.name, params, b.description);
  }
  return text;
}

}  // namespace cm::geom_occ::detail
