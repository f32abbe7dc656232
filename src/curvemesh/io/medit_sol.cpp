// MMG solution files .sol (text) and .solb (binary): the SolAtVertices
// keyword of the GMF layout. Symmetric tensors are kept in the file's order
// (m11 m12 m22 m13 m23 m33), which is the order MMG reads and writes: MMG
// swaps the 3rd and 4th values into its internal m11 m12 m13 m22 m23 m33.
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "curvemesh/io/atomic_file.hpp"
#include "curvemesh/io/formats.hpp"
#include "curvemesh/io/medit_common.hpp"

namespace cm::io {

namespace {

using gmf::Where;

// libMeshb's limit on the number of fields of one solution keyword (GmfMaxTyp).
constexpr std::int64_t kMaxFieldTypes = 1000;

// The field layout of a SolAtVertices record, and which field is returned.
struct SolHeader {
  std::vector<int> sizes;  // reals per vertex of each field
  std::size_t record_size = 0;
  std::size_t picked = 0;  // index of the first scalar or symmetric tensor field
  SolField::Type type = SolField::Type::kScalar;
};

// Builds the header from the field types; returns the reason it is unusable,
// or empty.
std::string make_header(const std::vector<std::int64_t>& types, SolHeader& h) {
  bool found = false;
  for (std::size_t f = 0; f < types.size(); ++f) {
    const int size = gmf::sol_type_size(types[f]);
    if (size == 0)
      return fmt::format("SolAtVertices: unknown field type {} (1 to 4 are defined)", types[f]);
    if (!found && (types[f] == gmf::kSolScalar || types[f] == gmf::kSolSymTensor)) {
      found = true;
      h.picked = f;
      h.type = types[f] == gmf::kSolScalar ? SolField::Type::kScalar : SolField::Type::kTensor;
    }
    h.sizes.push_back(size);
    h.record_size += static_cast<std::size_t>(size);
  }
  if (!found) {
    std::string list;
    for (std::int64_t t : types) list += fmt::format(" {}", t);
    return fmt::format(
        "SolAtVertices holds no scalar (type 1) or symmetric tensor (type 3) field (types:{})",
        list);
  }
  return {};
}

SolField read_text(std::string_view bytes, const std::string& file) {
  gmf::TextCursor in(bytes, file);
  std::string_view token = in.next();
  if (token.empty()) in.fail("not a solution file: the file is empty");
  if (token != "MeshVersionFormatted")
    in.fail(fmt::format("not a solution file: expected 'MeshVersionFormatted', found {}",
                        gmf::quote(token)));
  const std::int64_t version = in.read_int(Where{"MeshVersionFormatted"});
  if (version < 1 || version > 4)
    in.fail(fmt::format("unsupported MeshVersionFormatted {} (1 to 4 are defined)", version));
  bool has_dimension = false;
  bool has_solution = false;
  SolField sol;
  token = in.next();
  while (!token.empty() && token != "End") {
    if (!gmf::TextCursor::starts_keyword(token))
      in.fail(fmt::format("expected a keyword, found {} (does a count above match its records?)",
                          gmf::quote(token)));
    if (token == "MeshVersionFormatted") {
      in.fail("duplicate MeshVersionFormatted");
    } else if (token == "Dimension") {
      if (has_dimension) in.fail("duplicate Dimension");
      const std::int64_t dim = in.read_int(Where{"Dimension"});
      if (dim == 2) in.fail("Dimension 2 is not supported: curvemesh reads 3D solutions only");
      if (dim != 3) in.fail(fmt::format("invalid Dimension {} (expected 3)", dim));
      has_dimension = true;
    } else if (token == "SolAtVertices") {
      if (!has_dimension) in.fail("SolAtVertices before Dimension");
      if (has_solution) in.fail("duplicate SolAtVertices");
      has_solution = true;
      const std::int64_t count = in.read_int(Where{"SolAtVertices"});
      in.check_count("SolAtVertices", count, 1);
      const std::int64_t num_types = in.read_int(Where{"SolAtVertices"});
      if (num_types < 1 || num_types > kMaxFieldTypes)
        in.fail(fmt::format("SolAtVertices: number of fields {} is outside 1..{}", num_types,
                            kMaxFieldTypes));
      std::vector<std::int64_t> types;
      for (std::int64_t f = 0; f < num_types; ++f)
        types.push_back(in.read_int(Where{"SolAtVertices"}));
      SolHeader h;
      if (std::string reason = make_header(types, h); !reason.empty()) in.fail(std::move(reason));
      in.check_count("SolAtVertices", count, static_cast<std::int64_t>(h.record_size));
      sol.type = h.type;
      sol.values.reserve(static_cast<std::size_t>(count) *
                         static_cast<std::size_t>(h.sizes[h.picked]));
      for (std::int64_t r = 0; r < count; ++r) {
        const Where where{"SolAtVertices", r + 1, count};
        for (std::size_t f = 0; f < h.sizes.size(); ++f)
          for (int c = 0; c < h.sizes[f]; ++c) {
            const double value = in.read_real(where);
            if (f != h.picked) continue;
            if (!std::isfinite(value))
              in.fail(fmt::format("{}: value {} is not finite", where.describe(), value));
            sol.values.push_back(value);
          }
      }
    } else {
      token = in.skip_to_keyword();
      continue;
    }
    token = in.next();
  }
  if (token.empty()) in.fail("missing End keyword (is the file truncated?)");
  if (!has_solution) in.fail("no SolAtVertices section");
  return sol;
}

SolField read_binary(std::string_view bytes, const std::string& file) {
  const gmf::BinaryCursor in(bytes, file, ".solb");
  bool has_dimension = false;
  gmf::BinarySection solution;
  gmf::walk_binary_keywords(in, [&](const gmf::BinarySection& s) {
    if (s.code == gmf::kKwDimension) {
      if (has_dimension) in.fail(s.header, "duplicate Dimension");
      has_dimension = true;
      const std::int32_t dim = gmf::read_binary_dimension(in, s);
      if (dim == 2)
        in.fail(s.data, "Dimension 2 is not supported: curvemesh reads 3D solutions only");
      if (dim != 3) in.fail(s.data, fmt::format("invalid Dimension {} (expected 3)", dim));
    } else if (s.code == gmf::kKwSolAtVertices) {
      if (solution.code != 0) in.fail(s.header, "duplicate SolAtVertices");
      solution = s;
    }
  });
  if (solution.code == 0) in.fail(8, "no SolAtVertices keyword");

  const std::size_t types_at = solution.data + in.layout().int_bytes();
  if (solution.end < types_at + 4)
    in.fail(solution.data, "SolAtVertices: keyword ends before its field types");
  const std::int32_t num_types = in.i32_at(types_at);
  if (num_types < 1 || num_types > kMaxFieldTypes)
    in.fail(types_at, fmt::format("SolAtVertices: number of fields {} is outside 1..{}", num_types,
                                  kMaxFieldTypes));
  const std::size_t types_bytes = 4 * static_cast<std::size_t>(num_types);
  if (solution.end < types_at + 4 + types_bytes)
    in.fail(types_at, "SolAtVertices: keyword ends before its field types");
  std::vector<std::int64_t> types;
  for (std::int32_t f = 0; f < num_types; ++f)
    types.push_back(in.i32_at(types_at + 4 + 4 * static_cast<std::size_t>(f)));
  SolHeader h;
  if (std::string reason = make_header(types, h); !reason.empty())
    in.fail(types_at + 4, std::move(reason));

  const std::size_t rb = in.layout().real_bytes();
  const std::size_t record_bytes = h.record_size * rb;
  std::size_t at = 0;
  const std::int64_t count =
      gmf::read_binary_count(in, solution, "SolAtVertices", record_bytes, 4 + types_bytes, &at);
  std::size_t first = 0;
  for (std::size_t f = 0; f < h.picked; ++f) first += static_cast<std::size_t>(h.sizes[f]);
  const int size = h.sizes[h.picked];
  SolField sol;
  sol.type = h.type;
  sol.values.resize(static_cast<std::size_t>(count) * static_cast<std::size_t>(size));
  for (std::int64_t r = 0; r < count; ++r)
    for (int c = 0; c < size; ++c) {
      const std::size_t offset = at + static_cast<std::size_t>(r) * record_bytes +
                                 (first + static_cast<std::size_t>(c)) * rb;
      const double value = in.real_at(offset);
      if (!std::isfinite(value))
        in.fail(offset, fmt::format("SolAtVertices record {} of {}: value {} is not finite", r + 1,
                                    count, value));
      sol.values[static_cast<std::size_t>(r) * static_cast<std::size_t>(size) +
                 static_cast<std::size_t>(c)] = value;
    }
  return sol;
}

}  // namespace

SolField read_sol(std::string_view bytes, const std::string& file_name) {
  if (gmf::looks_binary(bytes)) return read_binary(bytes, file_name);
  return read_text(bytes, file_name);
}

void write_sol(const SolField& sol, const std::string& path, bool binary) {
  const std::size_t size = sol.type == SolField::Type::kScalar ? 1 : 6;
  if (sol.values.size() % size != 0)
    throw std::invalid_argument(fmt::format(
        "write_sol: {} values is not a whole number of 6-value tensors", sol.values.size()));
  for (std::size_t i = 0; i < sol.values.size(); ++i)
    if (!std::isfinite(sol.values[i]))
      throw std::invalid_argument(
          fmt::format("write_sol: value {} of vertex {} is not finite", sol.values[i], i / size));
  const std::size_t count = sol.values.size() / size;
  const int type = static_cast<int>(sol.type);

  AtomicFile file(path);
  gmf::OutputBuffer out(file);
  if (!binary) {
    auto& buf = out.text();
    fmt::format_to(fmt::appender(buf),
                   "MeshVersionFormatted 2\n\nDimension 3\n\nSolAtVertices\n{}\n1 {}\n", count,
                   type);
    for (std::size_t v = 0; v < count; ++v) {
      for (std::size_t c = 0; c < size; ++c) {
        if (c > 0) buf.push_back(' ');
        fmt::format_to(fmt::appender(buf), "{}", sol.values[v * size + c]);
      }
      buf.push_back('\n');
      out.maybe_flush();
    }
    fmt::format_to(fmt::appender(buf), "\nEnd\n");
  } else {
    const bool wide_ints =
        count > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
    const auto file_bytes = [&](int version) {
      const gmf::BinaryLayout layout{false, version};
      const std::uint64_t header = 4 + layout.position_bytes();
      return 8 + (header + 4) + (header + layout.int_bytes() + 8 + 8 * sol.values.size()) + header;
    };
    const int version = gmf::choose_binary_version(file_bytes(2), wide_ints);
    const std::uint64_t header = 4 + gmf::BinaryLayout{false, version}.position_bytes();
    out.put<std::int32_t>(1);
    out.put<std::int32_t>(version);
    gmf::put_keyword(out, version, gmf::kKwDimension, 8 + header + 4, -1);
    out.put<std::int32_t>(3);
    gmf::put_keyword(out, version, gmf::kKwSolAtVertices, file_bytes(version) - header,
                     static_cast<std::int64_t>(count));
    out.put<std::int32_t>(1);
    out.put<std::int32_t>(type);
    for (double value : sol.values) {
      out.put<double>(value);
      out.maybe_flush();
    }
    gmf::put_keyword(out, version, gmf::kKwEnd, 0, -1);
  }
  out.flush();
  file.commit();
}

}  // namespace cm::io
