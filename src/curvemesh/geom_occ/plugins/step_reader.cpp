// Plugin: reading STEP files (TKSTEP, TKXSBase), keeping the file's length
// unit (the translator would otherwise convert to millimetres). The caller
// checked the header and holds the XSTEP lock.
#include <algorithm>
#include <cctype>
#include <optional>
#include <string_view>

#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Reader.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/plugin.hpp"

namespace cm::geom_occ::detail {

namespace {

struct LengthUnit {
  std::string_view name;   // as reported by units()
  double millimetres = 0;  // size of one unit, in mm (XSTEP's reference unit)
};

// STEP SI unit names ("MILLIMETRE", "metre") and conversion-based names ("INCH").
std::optional<LengthUnit> step_unit(std::string name) {
  static const std::pair<std::string_view, LengthUnit> kUnits[] = {
      {"millimetre", {"mm", 1}},      {"millimeter", {"mm", 1}},
      {"centimetre", {"cm", 10}},     {"centimeter", {"cm", 10}},
      {"decimetre", {"dm", 100}},     {"decimeter", {"dm", 100}},
      {"metre", {"m", 1000}},         {"meter", {"m", 1000}},
      {"kilometre", {"km", 1e6}},     {"kilometer", {"km", 1e6}},
      {"micrometre", {"um", 1e-3}},   {"micrometer", {"um", 1e-3}},
      {"micron", {"um", 1e-3}},       {"nanometre", {"nm", 1e-6}},
      {"inch", {"inch", 25.4}},       {"foot", {"ft", 304.8}},
      {"feet", {"ft", 304.8}},        {"mile", {"mile", 1609344}},
  };
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const auto& [key, unit] : kUnits)
    if (name == key) return unit;
  return std::nullopt;
}

// Multiplies an XSTEP real parameter for the lifetime of the object (under
// the caller's XSTEP lock).
class ScopedStaticReal {
 public:
  ScopedStaticReal(const char* name, double factor) : name_(name), saved_(Interface_Static::RVal(name)) {
    Interface_Static::SetRVal(name_, saved_ * factor);
  }
  ~ScopedStaticReal() { Interface_Static::SetRVal(name_, saved_); }
  ScopedStaticReal(const ScopedStaticReal&) = delete;
  ScopedStaticReal& operator=(const ScopedStaticReal&) = delete;

 private:
  const char* name_;
  double saved_;
};

ReadShape read_step(const std::string& path) {
  STEPControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
    throw InputError(path, -1, -1, "the STEP parser rejected the file (syntax errors or truncated)");
  ReadShape out;
  double max_precision_scale = 1;
  TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
  reader.FileUnits(lengths, angles, solid_angles);
  if (!lengths.IsEmpty()) {
    if (const auto unit = step_unit(lengths.First().ToCString())) {
      // Translate in the file's own unit: the system unit is in mm.
      reader.SetSystemLengthUnit(unit->millimetres);
      out.units = std::string(unit->name);
      max_precision_scale = 1 / unit->millimetres;
    } else {
      // A unit XSTEP knows but we cannot name: it converts to mm.
      out.units = "mm";
    }
  }
  // The healing's largest tolerance is a length in the system unit (1 mm by
  // default): scale it so healing does the same whatever the file's unit.
  const ScopedStaticReal max_precision("read.maxprecision.val", max_precision_scale);
  if (reader.NbRootsForTransfer() == 0 || reader.TransferRoots() == 0)
    throw GeometryError(fmt::format("{}: the STEP file holds no transferable shape", path));
  out.shape = reader.OneShape();
  return out;
}

}  // namespace

}  // namespace cm::geom_occ::detail

CM_OCC_PLUGIN(.read_file = cm::geom_occ::detail::read_step)
