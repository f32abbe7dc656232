// Plugin: the general fuse of an assembly's solids (TKBO). It splits the
// solids against each other and merges coincident faces, edges and vertices,
// so touching solids share their interface; each piece stays a solid.
#include <BOPAlgo_Builder.hxx>
#include <BRep_Builder.hxx>
#include <Message_Report.hxx>
#include <Standard_SStream.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS_Compound.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/plugin.hpp"

namespace cm::geom_occ::detail {

namespace {

TopoDS_Shape fuse_solids(const std::vector<TopoDS_Solid>& solids, double fuzz, const std::string& source) {
  BOPAlgo_Builder fuse;
  for (const TopoDS_Solid& s : solids) fuse.AddArgument(s);
  fuse.SetRunParallel(false);  // deterministic and polite to the caller's threads
  fuse.SetFuzzyValue(fuzz);
  fuse.Perform();
  if (fuse.HasErrors()) {
    Standard_SStream report;
    fuse.DumpErrors(report);
    throw GeometryError(fmt::format("{}: the {} solids cannot be made conformal: {}", source, solids.size(),
                                    report.str()));
  }
  TopoDS_Compound result;
  BRep_Builder builder;
  builder.MakeCompound(result);
  for (TopExp_Explorer ex(fuse.Shape(), TopAbs_SOLID); ex.More(); ex.Next()) builder.Add(result, ex.Current());
  return result;
}

}  // namespace

}  // namespace cm::geom_occ::detail

CM_OCC_PLUGIN(.fuse_solids = cm::geom_occ::detail::fuse_solids)
