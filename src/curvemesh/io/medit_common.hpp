#pragma once
// Private to the io module: what the Medit mesh (.mesh/.meshb) and MMG
// solution (.sol/.solb) readers and writers share. Both follow libMeshb's
// "GMF" layout. Header-only, so each format's source file (and its fuzz
// target) builds on its own.
//
// Text files are whitespace-separated tokens: keywords, then numbers; '#'
// starts a comment that runs to the end of the line.
//
// Binary files (libMeshb 7): the int32 1 in the writer's byte order (read as
// 16777216 when the bytes are swapped), then the int32 version:
//   version  reals    integers  keyword positions
//   1        float32  int32     int32
//   2        float64  int32     int32
//   3        float64  int32     int64
//   4        float64  int64     int64
// then keyword records: int32 keyword code, the absolute position of the next
// keyword (0 after the last one), for keywords with records their count (an
// integer of the version's size), for solution keywords an int32 number of
// fields and one int32 type per field, then the records. The first keyword is
// Dimension, whose value is always an int32.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>

#include "curvemesh/core/error.hpp"
#include "curvemesh/io/atomic_file.hpp"

namespace cm::io::gmf {

// Keyword codes of libMeshb 7 (enum GmfKwdCod) that curvemesh handles. The
// version is not a keyword in binary files: it follows the endianness word.
inline constexpr int kKwDimension = 3;
inline constexpr int kKwVertices = 4;
inline constexpr int kKwEdges = 5;
inline constexpr int kKwTriangles = 6;
inline constexpr int kKwTetrahedra = 8;
inline constexpr int kKwEnd = 54;
inline constexpr int kKwSolAtVertices = 62;

// Solution field types in a SolAtVertices header (GmfSca .. GmfMat).
inline constexpr int kSolScalar = 1;
inline constexpr int kSolVector = 2;
inline constexpr int kSolSymTensor = 3;
inline constexpr int kSolMatrix = 4;

/// Reals per vertex of a 3D solution field of `type`; 0 for an unknown type.
inline int sol_type_size(std::int64_t type) {
  switch (type) {
    case kSolScalar:
      return 1;
    case kSolVector:
      return 3;
    case kSolSymTensor:
      return 6;
    case kSolMatrix:
      return 9;
    default:
      return 0;
  }
}

/// Keywords of high-order elements (EdgesP2..TetrahedraP4). libMeshb leaves
/// their node order to separate *Ordering keywords, so curvemesh refuses them
/// rather than guess.
inline std::string_view high_order_keyword_name(int code) {
  switch (code) {
    case 24:
      return "TrianglesP2";
    case 25:
      return "EdgesP2";
    case 30:
      return "TetrahedraP2";
    case 90:
      return "TrianglesP3";
    case 91:
      return "TrianglesP4";
    case 92:
      return "EdgesP3";
    case 93:
      return "EdgesP4";
    case 96:
      return "TetrahedraP3";
    case 97:
      return "TetrahedraP4";
    default:
      return "";
  }
}
inline bool is_high_order_keyword(int code) { return !high_order_keyword_name(code).empty(); }
inline bool is_high_order_keyword(std::string_view name) {
  for (std::string_view base : {"EdgesP", "TrianglesP", "TetrahedraP"})
    if (name.size() == base.size() + 1 && name.substr(0, base.size()) == base &&
        name.back() >= '2' && name.back() <= '4')
      return true;
  return false;
}

/// A token for an error message: at most 40 characters, non-printable bytes
/// escaped, in quotes.
inline std::string quote(std::string_view token) {
  std::string out = "'";
  for (std::size_t i = 0; i < std::min<std::size_t>(token.size(), 40); ++i) {
    const auto c = static_cast<unsigned char>(token[i]);
    if (c >= 0x20 && c < 0x7f)
      out += static_cast<char>(c);
    else
      out += fmt::format("\\x{:02x}", c);
  }
  if (token.size() > 40) out += "...";
  return out + "'";
}

/// Where a number is read, for error messages: "<section> record r of n", or
/// just the section when `record` is 0.
struct Where {
  std::string_view section;
  std::int64_t record = 0;
  std::int64_t count = 0;
  std::string describe() const {
    return record > 0 ? fmt::format("{} record {} of {}", section, record, count)
                      : std::string(section);
  }
};

inline std::uint32_t swap_bytes(std::uint32_t v) { return __builtin_bswap32(v); }
inline std::uint64_t swap_bytes(std::uint64_t v) { return __builtin_bswap64(v); }

inline bool fits_int32(std::int64_t v) {
  return v >= std::numeric_limits<std::int32_t>::min() &&
         v <= std::numeric_limits<std::int32_t>::max();
}

/// Token reader over a text GMF file that tracks 1-based line numbers.
class TextCursor {
 public:
  TextCursor(std::string_view text, const std::string& file) : text_(text), file_(file) {
    if (text_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;  // UTF-8 byte order mark
  }

  /// The next token, or an empty view at the end of the input (line() then
  /// stays on the last token, which is where a truncated file is cut).
  std::string_view next() {
    const std::size_t n = text_.size();
    for (;;) {
      while (pos_ < n && is_space(text_[pos_])) {
        if (text_[pos_] == '\n') ++line_;
        ++pos_;
      }
      if (pos_ < n && text_[pos_] == '#') {
        while (pos_ < n && text_[pos_] != '\n') ++pos_;
        continue;
      }
      break;
    }
    if (pos_ == n) return {};
    token_line_ = line_;
    const std::size_t start = pos_;
    while (pos_ < n && !is_space(text_[pos_])) ++pos_;
    return text_.substr(start, pos_ - start);
  }

  /// Skips the numbers of a section curvemesh does not read; returns the next
  /// token that starts with a letter (the next keyword), or empty at the end.
  std::string_view skip_to_keyword() {
    for (;;) {
      const std::string_view token = next();
      if (token.empty() || starts_keyword(token)) return token;
    }
  }

  std::int64_t read_int(const Where& where) {
    const std::string_view token = next_number(where);
    std::int64_t value = 0;
    const char* first = token.data() + (token.size() > 1 && token[0] == '+' ? 1 : 0);
    const char* last = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr != last)
      fail(fmt::format("{}: expected an integer, found {}", where.describe(), quote(token)));
    return value;
  }

  /// A real number; NaN and infinities are returned as parsed (callers that
  /// need finite values check and report them).
  double read_real(const Where& where) {
    const std::string_view token = next_number(where);
    double value = 0;
    const char* first = token.data() + (token.size() > 1 && token[0] == '+' ? 1 : 0);
    const char* last = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ptr != last || (ec != std::errc() && ec != std::errc::result_out_of_range))
      fail(fmt::format("{}: expected a number, found {}", where.describe(), quote(token)));
    if (ec == std::errc::result_out_of_range)
      fail(fmt::format("{}: number {} is out of the range of a double", where.describe(),
                       quote(token)));
    return value;
  }

  /// Reads a record count and checks it against the bytes left.
  std::int64_t read_count(std::string_view section, std::int64_t numbers_per_record) {
    const std::int64_t count = read_int(Where{section});
    check_count(section, count, numbers_per_record);
    return count;
  }

  /// Fails unless `count` records of `numbers_per_record` numbers can fit in
  /// the bytes left (each number takes at least two characters), so that an
  /// absurd count is refused before anything is allocated for it.
  void check_count(std::string_view section, std::int64_t count,
                   std::int64_t numbers_per_record) const {
    if (count < 0) fail(fmt::format("{}: negative count {}", section, count));
    const auto remaining = static_cast<std::int64_t>(text_.size() - pos_);
    if (count > 0 && (count > remaining || count * 2 * numbers_per_record - 1 > remaining))
      fail(fmt::format("{}: count {} is larger than the rest of the file can hold ({} bytes)",
                       section, count, remaining));
  }

  /// Line of the token returned last.
  std::int64_t line() const { return token_line_; }
  const std::string& file() const { return file_; }

  [[noreturn]] void fail(std::string reason) const {
    throw InputError(file_, token_line_, -1, std::move(reason));
  }

  static bool starts_keyword(std::string_view token) {
    const char c = token.empty() ? '\0' : token[0];
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
  }

 private:
  static bool is_space(char c) {
    return c == ' ' || c == '\n' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
  }

  std::string_view next_number(const Where& where) {
    const std::string_view token = next();
    if (token.empty()) fail(fmt::format("unexpected end of file in {}", where.describe()));
    return token;
  }

  std::string_view text_;
  const std::string& file_;
  std::size_t pos_ = 0;
  std::int64_t line_ = 1;
  std::int64_t token_line_ = 1;
};

/// Sizes of the binary fields of one file version (see the table on top).
struct BinaryLayout {
  bool swap = false;
  int version = 2;
  std::size_t real_bytes() const { return version == 1 ? 4 : 8; }
  std::size_t int_bytes() const { return version == 4 ? 8 : 4; }
  std::size_t position_bytes() const { return version >= 3 ? 8 : 4; }
};

/// True if `bytes` starts with the binary endianness word (1 in either byte
/// order); a text file cannot start with those bytes.
inline bool looks_binary(std::string_view bytes) {
  if (bytes.size() < 4) return false;
  std::uint32_t code = 0;
  std::memcpy(&code, bytes.data(), 4);
  return code == 1u || code == 0x01000000u;
}

/// Bounds-checked reads of a binary GMF file, in the file's byte order.
class BinaryCursor {
 public:
  /// Reads the endianness word and the version; `kind` (".meshb", ".solb")
  /// names the format in error messages.
  BinaryCursor(std::string_view bytes, const std::string& file, std::string_view kind)
      : bytes_(bytes), file_(file) {
    if (bytes_.size() < 8)
      fail(0, fmt::format("file too short for a {} header ({} bytes)", kind, bytes_.size()));
    layout_.swap = u32_at(0) != 1u;
    const std::int32_t version = i32_at(4);
    if (version < 1 || version > 4)
      fail(4, fmt::format("unsupported {} version {} (1 to 4 are defined)", kind, version));
    layout_.version = version;
  }

  const BinaryLayout& layout() const { return layout_; }
  std::size_t size() const { return bytes_.size(); }

  /// Fails unless `n` bytes are available at `offset`.
  void require(std::size_t offset, std::size_t n, std::string_view what) const {
    if (offset > bytes_.size() || n > bytes_.size() - offset)
      fail(offset, fmt::format("file ends inside {} ({} bytes needed, {} left)", what, n,
                               offset > bytes_.size() ? 0 : bytes_.size() - offset));
  }

  std::int32_t i32_at(std::size_t offset) const {
    return static_cast<std::int32_t>(u32_at(offset));
  }
  std::int64_t i64_at(std::size_t offset) const {
    check(offset, 8);
    std::uint64_t v = 0;
    std::memcpy(&v, bytes_.data() + offset, 8);
    return static_cast<std::int64_t>(layout_.swap ? swap_bytes(v) : v);
  }
  /// An integer field of the version's size.
  std::int64_t int_at(std::size_t offset) const {
    return layout_.version == 4 ? i64_at(offset) : i32_at(offset);
  }
  /// A keyword position of the version's size.
  std::int64_t position_at(std::size_t offset) const {
    return layout_.version >= 3 ? i64_at(offset) : i32_at(offset);
  }
  /// A real field of the version's size.
  double real_at(std::size_t offset) const {
    if (layout_.version == 1) return static_cast<double>(std::bit_cast<float>(u32_at(offset)));
    return std::bit_cast<double>(i64_at(offset));
  }

  [[noreturn]] void fail(std::size_t offset, std::string reason) const {
    throw InputError(file_, -1, static_cast<std::int64_t>(offset), std::move(reason));
  }

 private:
  std::uint32_t u32_at(std::size_t offset) const {
    check(offset, 4);
    std::uint32_t v = 0;
    std::memcpy(&v, bytes_.data() + offset, 4);
    return layout_.swap ? swap_bytes(v) : v;
  }
  void check(std::size_t offset, std::size_t n) const {
    if (offset > bytes_.size() || n > bytes_.size() - offset)
      fail(offset, "unexpected end of file");
  }

  std::string_view bytes_;
  const std::string& file_;
  BinaryLayout layout_;
};

/// One keyword of a binary file: its code, where its header starts, where the
/// data after the next-keyword position starts, and where the next keyword
/// starts (the file size for the last one).
struct BinarySection {
  int code = 0;
  std::size_t header = 0;
  std::size_t data = 0;
  std::size_t end = 0;
};

/// Walks the keyword chain from byte 8 up to End or a zero next position,
/// calling visit(section) for each keyword. Every next position must lie
/// past the current keyword's header and inside the file, so the walk always
/// ends, after at most size/8 keywords. The first keyword must be Dimension.
template <class Visit>
void walk_binary_keywords(const BinaryCursor& in, Visit&& visit) {
  const std::size_t header_bytes = 4 + in.layout().position_bytes();
  std::size_t offset = 8;
  for (bool first = true;; first = false) {
    in.require(offset, header_bytes, "a keyword header");
    BinarySection s;
    s.code = in.i32_at(offset);
    s.header = offset;
    s.data = offset + header_bytes;
    const std::int64_t next = in.position_at(offset + 4);
    if (first && s.code != kKwDimension)
      in.fail(offset, fmt::format("expected the Dimension keyword (code {}) first, found code {}",
                                  kKwDimension, s.code));
    if (next != 0 &&
        (next < static_cast<std::int64_t>(s.data) || next > static_cast<std::int64_t>(in.size())))
      in.fail(offset + 4, fmt::format("keyword code {}: next keyword position {} is outside {}..{}",
                                      s.code, next, s.data, in.size()));
    s.end = next == 0 ? in.size() : static_cast<std::size_t>(next);
    visit(s);
    if (next == 0 || s.code == kKwEnd) return;
    offset = s.end;
  }
}

/// Reads the Dimension keyword's int32 value.
inline std::int32_t read_binary_dimension(const BinaryCursor& in, const BinarySection& s) {
  if (s.end < s.data + 4) in.fail(s.data, "Dimension keyword holds no value");
  return in.i32_at(s.data);
}

/// Reads the record count of a keyword and checks that `count` records of
/// `record_bytes` each, starting `extra_header` bytes after the count, fit
/// before the next keyword. Returns the count; `records` gets their offset.
inline std::int64_t read_binary_count(const BinaryCursor& in, const BinarySection& s,
                                      std::string_view name, std::size_t record_bytes,
                                      std::size_t extra_header, std::size_t* records) {
  const std::size_t int_bytes = in.layout().int_bytes();
  if (s.end < s.data + int_bytes)
    in.fail(s.data, fmt::format("{}: keyword ends before its count", name));
  const std::int64_t count = in.int_at(s.data);
  if (count < 0) in.fail(s.data, fmt::format("{}: negative count {}", name, count));
  *records = s.data + int_bytes + extra_header;
  const std::size_t available = s.end > *records ? s.end - *records : 0;
  if (s.end < *records ||
      static_cast<std::uint64_t>(count) > available / std::max<std::size_t>(record_bytes, 1))
    in.fail(s.data,
            fmt::format(
                "{}: count {} of {}-byte records does not fit in the {} bytes the keyword holds",
                name, count, record_bytes, available));
  return count;
}

/// Collects output in memory and hands it to the file in large blocks.
class OutputBuffer {
 public:
  explicit OutputBuffer(AtomicFile& out) : out_(out) {}
  OutputBuffer(const OutputBuffer&) = delete;
  OutputBuffer& operator=(const OutputBuffer&) = delete;

  fmt::memory_buffer& text() { return buf_; }
  template <class T>
  void put(T value) {
    const char* p = reinterpret_cast<const char*>(&value);
    buf_.append(p, p + sizeof(T));
  }
  /// Writes the buffer out once it holds more than a megabyte.
  void maybe_flush() {
    if (buf_.size() > (1u << 20)) flush();
  }
  void flush() {
    out_.write(buf_.data(), buf_.size());
    buf_.clear();
  }

 private:
  AtomicFile& out_;
  fmt::memory_buffer buf_;
};

/// Version for a binary file of `total_bytes` whose integers need 64 bits or
/// not: 2 when positions fit libMeshb's signed 32-bit words, else 3; 4 when
/// integers do not fit 32 bits.
inline int choose_binary_version(std::uint64_t total_bytes, bool needs_64bit_ints) {
  if (needs_64bit_ints) return 4;
  return total_bytes <= static_cast<std::uint64_t>(std::numeric_limits<std::int32_t>::max()) ? 2
                                                                                             : 3;
}

/// Writes a keyword header: code, next position, and the count when
/// `count >= 0`, in the sizes of `version`.
inline void put_keyword(OutputBuffer& out, int version, std::int32_t code,
                        std::uint64_t next_position, std::int64_t count) {
  out.put<std::int32_t>(code);
  if (version >= 3)
    out.put<std::int64_t>(static_cast<std::int64_t>(next_position));
  else
    out.put<std::int32_t>(static_cast<std::int32_t>(next_position));
  if (count >= 0) {
    if (version == 4)
      out.put<std::int64_t>(count);
    else
      out.put<std::int32_t>(static_cast<std::int32_t>(count));
  }
}

}  // namespace cm::io::gmf
