#include "occ_reference.hpp"

#include <algorithm>
#include <filesystem>
#include <stdexcept>

#include <BOPAlgo_Builder.hxx>
#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <STEPControl_Reader.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopoDS_Compound.hxx>

namespace cm::test {

std::vector<std::string> model_files() {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(CM_SHARED_DIR) + "/models")) {
    const std::string ext = entry.path().extension().string();
    if (ext == ".step" || ext == ".stp" || ext == ".brep") files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

Reference read_reference(const std::string& path) {
  Reference ref;
  if (path.ends_with(".brep")) {
    BRep_Builder builder;
    if (!BRepTools::Read(ref.raw, path.c_str(), builder)) throw std::runtime_error("read " + path);
  } else {
    STEPControl_Reader reader;
    if (reader.ReadFile(path.c_str()) != IFSelect_RetDone) throw std::runtime_error("read " + path);
    reader.TransferRoots();
    ref.raw = reader.OneShape();
  }
  BRep_Builder builder;
  TopoDS_Compound compound;
  builder.MakeCompound(compound);
  TopTools_ListOfShape solids;
  for (TopExp_Explorer ex(ref.raw, TopAbs_SOLID); ex.More(); ex.Next()) solids.Append(ex.Current());
  if (solids.Extent() > 1) {
    BOPAlgo_Builder fuse;
    fuse.SetArguments(solids);
    fuse.Perform();
    for (TopExp_Explorer ex(fuse.Shape(), TopAbs_SOLID); ex.More(); ex.Next())
      builder.Add(compound, ex.Current());
  } else {
    for (const TopoDS_Shape& s : solids) builder.Add(compound, s);
  }
  ref.solids = compound;
  TopExp::MapShapes(compound, TopAbs_VERTEX, ref.vertices);
  TopExp::MapShapes(compound, TopAbs_EDGE, ref.edges);
  TopExp::MapShapes(compound, TopAbs_FACE, ref.faces);
  TopExp::MapShapes(compound, TopAbs_SOLID, ref.solids_map);
  return ref;
}

double mm_per_unit(const std::string& units) {
  if (units.empty() || units == "mm") return 1;
  if (units == "cm") return 10;
  if (units == "m") return 1000;
  if (units == "inch") return 25.4;
  if (units == "ft") return 304.8;
  throw std::runtime_error("unexpected unit " + units);
}

std::string base_name(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

}  // namespace cm::test
