// load_model: read or build the shape, make conformal solids, index them.
#include "curvemesh/geom_occ/load.hpp"

#include <Standard_Failure.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/builtin_catalog.hpp"
#include "curvemesh/geom_occ/detail/occ_model.hpp"
#include "curvemesh/geom_occ/detail/occ_shapes.hpp"
#include "curvemesh/geom_occ/detail/plugin.hpp"

namespace cm::geom_occ {

std::unique_ptr<geom::Model> load_model(const std::string& model, const LoadOptions& options) {
  const bool builtin = model.rfind("builtin:", 0) == 0;
  const detail::ReadShape read = builtin ? detail::plugin(detail::Plugin::kBuiltin).make_builtin(model)
                                         : detail::read_cad_file(model);
  const TopoDS_Shape solids = detail::make_conformal_solids(read, options, model);
  try {
    return std::make_unique<detail::OccModel>(solids, read.units);
  } catch (const GeometryError& e) {
    throw GeometryError(fmt::format("{}: {}", model, e.what()));
  } catch (const Standard_Failure& e) {
    throw GeometryError(fmt::format("{}: OpenCASCADE failed while indexing the model: {} ({})",
                                    model, e.GetMessageString(), e.DynamicType()->Name()));
  }
}

std::string builtin_help() { return detail::builtin_help_text(); }

}  // namespace cm::geom_occ
