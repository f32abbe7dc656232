// Reading STEP, IGES and B-rep files into a TopoDS shape, keeping the file's
// length unit (the translators would otherwise convert to millimetres).
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <sstream>
#include <string_view>

#include <BRepTools.hxx>
#include <BRep_Builder.hxx>
#include <IFSelect_ReturnStatus.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Reader.hxx>
#include <Standard_Failure.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>
#include <TCollection_HAsciiString.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/occ_shapes.hpp"

namespace cm::geom_occ::detail {

namespace {

// XSTEP keeps its parameters and unit factors in process-wide statics.
std::mutex g_xstep_mutex;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

struct LengthUnit {
  std::string_view name;      // as reported by units()
  double millimetres = 0;     // size of one unit, in mm (XSTEP's reference unit)
};

// STEP SI unit names ("MILLIMETRE", "metre") and conversion-based names ("INCH").
std::optional<LengthUnit> step_unit(const std::string& file_name) {
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
  const std::string name = lower(file_name);
  for (const auto& [key, unit] : kUnits)
    if (name == key) return unit;
  return std::nullopt;
}

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

// Multiplies an XSTEP real parameter for the lifetime of the object (under
// g_xstep_mutex).
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

enum class Format { kStep, kIges, kBrep };

Format format_of(const std::string& path) {
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  if (ext == ".step" || ext == ".stp") return Format::kStep;
  if (ext == ".iges" || ext == ".igs") return Format::kIges;
  if (ext == ".brep" || ext == ".brp") return Format::kBrep;
  throw InputError(path, -1, -1,
                   fmt::format("unknown model file extension '{}' (expected .step, .stp, "
                               ".iges, .igs or .brep)",
                               ext));
}

// The first bytes of the file, to tell "wrong content" from "damaged file".
std::string file_head(const std::string& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(path, -1, -1, fmt::format("cannot open file: {}", std::strerror(errno)));
  std::string head(n, '\0');
  in.read(head.data(), static_cast<std::streamsize>(n));
  head.resize(static_cast<std::size_t>(in.gcount()));
  return head;
}

std::string trim_left(const std::string& s) {
  std::size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  return s.substr(i);
}

ReadShape read_step(const std::string& path) {
  if (trim_left(file_head(path, 256)).rfind("ISO-10303-21", 0) != 0)
    throw InputError(path, 1, -1,
                     "not a STEP file: it does not start with 'ISO-10303-21;' (ISO 10303-21 "
                     "exchange structure)");
  std::lock_guard<std::mutex> lock(g_xstep_mutex);
  STEPControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
    throw InputError(path, -1, -1, "the STEP parser rejected the file (syntax errors or truncated)");
  ReadShape out;
  double max_precision_scale = 1;
  TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
  reader.FileUnits(lengths, angles, solid_angles);
  if (!lengths.IsEmpty()) {
    const std::string declared = lengths.First().ToCString();
    if (const auto unit = step_unit(declared)) {
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

// IGES is fixed-format: 80-column records whose column 73 names the section,
// S(tart) first (F/B for the binary forms, C for compressed ASCII).
bool looks_like_iges(const std::string& head) {
  const std::size_t eol = head.find_first_of("\r\n");
  const std::string first = head.substr(0, eol);
  if (first.size() < 73) return false;
  const char section = first[72];
  return section == 'S' || section == 'G' || section == 'C' || section == 'B' || section == 'F';
}

ReadShape read_iges(const std::string& path) {
  if (!looks_like_iges(file_head(path, 256)))
    throw InputError(path, 1, -1,
                     "not an IGES file: the first record is not an 80-column Start-section line");
  std::lock_guard<std::mutex> lock(g_xstep_mutex);
  IGESControl_Reader reader;
  if (reader.ReadFile(path.c_str()) != IFSelect_RetDone)
    throw InputError(path, -1, -1, "not a readable IGES file (the IGES parser rejected it)");
  ReadShape out;
  const Handle(IGESData_IGESModel) model = reader.IGESModel();
  if (model.IsNull())
    throw InputError(path, -1, -1, "not a readable IGES file (no IGES model)");
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

ReadShape read_brep(const std::string& path) {
  const std::string head = file_head(path, 256);
  if (head.find("CASCADE Topology") == std::string::npos)
    throw InputError(path, 1, -1,
                     "not an OpenCASCADE B-rep file: no 'CASCADE Topology' header");
  ReadShape out;
  BRep_Builder builder;
  // The B-rep reader reports its complaints on std::cout; catch them so the
  // user sees one error line that carries the reader's reason.
  std::ostringstream complaints;
  std::streambuf* const saved = std::cout.rdbuf(complaints.rdbuf());
  bool ok = false;
  try {
    ok = BRepTools::Read(out.shape, path.c_str(), builder);
  } catch (...) {
    std::cout.rdbuf(saved);
    throw;
  }
  std::cout.rdbuf(saved);
  if (!ok || out.shape.IsNull()) {
    std::string reason = complaints.str();
    while (!reason.empty() && std::isspace(static_cast<unsigned char>(reason.back()))) reason.pop_back();
    for (std::size_t at = reason.find('\n'); at != std::string::npos; at = reason.find('\n', at))
      reason.replace(at, 1, "; ");
    throw InputError(path, -1, -1,
                     "the B-rep reader rejected the file (damaged or truncated)" +
                         (reason.empty() ? std::string() : ": " + reason));
  }
  return out;
}

}  // namespace

ReadShape read_cad_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw InputError(path, -1, -1, "no such file");
  if (fs::is_directory(status)) throw InputError(path, -1, -1, "is a directory, not a model file");
  const Format format = format_of(path);
  if (fs::file_size(path, ec) == 0 || ec) throw InputError(path, -1, -1, "empty file");
  try {
    switch (format) {
      case Format::kStep: return read_step(path);
      case Format::kIges: return read_iges(path);
      case Format::kBrep: return read_brep(path);
    }
  } catch (const Standard_Failure& e) {
    throw InputError(path, -1, -1,
                     fmt::format("the file could not be read: {} ({})", e.GetMessageString(),
                                 e.DynamicType()->Name()));
  }
  throw InternalError("unhandled model format");
}

}  // namespace cm::geom_occ::detail
