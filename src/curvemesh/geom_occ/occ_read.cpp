// Reading STEP, IGES and B-rep files into a TopoDS shape: the format by
// extension, the header checked here, STEP and IGES parsed by their plugins.
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
#include <Standard_Failure.hxx>

#include "curvemesh/core/error.hpp"
#include "curvemesh/geom_occ/detail/plugin.hpp"

namespace cm::geom_occ::detail {

namespace {

// XSTEP keeps its parameters and unit factors in process-wide statics.
std::mutex g_xstep_mutex;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

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
  const PluginTable& reader = plugin(Plugin::kStep);
  std::lock_guard<std::mutex> lock(g_xstep_mutex);
  return reader.read_file(path);
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
  const PluginTable& reader = plugin(Plugin::kIges);
  std::lock_guard<std::mutex> lock(g_xstep_mutex);
  return reader.read_file(path);
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
