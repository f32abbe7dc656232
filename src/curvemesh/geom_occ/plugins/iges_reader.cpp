// Plugin: reading IGES files (TKIGES, TKXSBase), keeping the file's length
// unit. The caller checked the first record and holds the XSTEP lock.
#include <optional>
#include <string_view>

#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/plugin.hpp"

namespace cm::geom_occ::detail {

namespace {

struct LengthUnit {
  std::string_view name;   // as reported by units()
  double millimetres = 0;  // size of one unit, in mm (XSTEP's reference unit)
};

// IGES global-section unit flags (IGES 5.3, parameter 14).
std::optional<LengthUnit> iges_unit(int flag) {
  switch (flag) {
    case 1: return LengthUnit{"inch", 25.4};
    case 2: return LengthUnit{"mm", 1};
    case 4: return LengthUnit{"ft", 304.8};
    case 5: return LengthUnit{"mile", 1609344};
    case 6: return LengthUnit{"m", 1000};
    case 7: return LengthUnit{"km", 1e6};
    case 8: return LengthUnit{"mil", 0.0254};
    case 9: return LengthUnit{"um", 1e-3};
    case 10: return LengthUnit{"cm", 10};
    case 11: return LengthUnit{"uin", 2.54e-5};
    default: return std::nullopt;
  }
}

ReadShape read_iges(const std::string& path) {
  IGESControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
    throw InputError(path, -1, -1, "not a readable IGES file (the IGES parser rejected it)");
  ReadShape out;
  const Handle(IGESData_IGESModel) model = reader.IGESModel();
  if (model.IsNull()) throw InputError(path, -1, -1, "not a readable IGES file (no IGES model)");
  IGESData_GlobalSection section = model->GlobalSection();
  if (const auto unit = iges_unit(section.UnitFlag())) {
    section.SetCascadeUnit(unit->millimetres);
    model->SetGlobalSection(section);
    out.units = std::string(unit->name);
  } else {
    out.units = "mm";
  }
  if (reader.NbRootsForTransfer() == 0 || reader.TransferRoots() == 0)
    throw GeometryError(fmt::format("{}: the IGES file holds no transferable shape", path));
  out.shape = reader.OneShape();
  return out;
}

}  // namespace

}  // namespace cm::geom_occ::detail

CM_OCC_PLUGIN(.read_file = cm::geom_occ::detail::read_iges)
