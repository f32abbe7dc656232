#pragma once
// Internal to geom_occ (includes OpenCASCADE): the stages of load_model that
// produce the final TopoDS shape — reading files, built-in shapes, healing and
// making conformal solids. Never include this header outside geom_occ.
#include <string>

#include <TopoDS_Shape.hxx>

#include "curvemesh/geom_occ/load.hpp"

namespace cm::geom_occ::detail {

/// A shape as read, with the length unit it is expressed in ("" if unknown).
struct ReadShape {
  TopoDS_Shape shape;
  std::string units;
};

/// Reads a STEP, IGES or B-rep file chosen by extension; throws cm::InputError.
ReadShape read_cad_file(const std::string& path);

/// Heals, sews and fuses `read` into a compound of conformal solids (see
/// load.hpp for the policy). `source` names the model in error messages.
TopoDS_Shape make_conformal_solids(const ReadShape& read, const LoadOptions& options,
                                   const std::string& source);

}  // namespace cm::geom_occ::detail
