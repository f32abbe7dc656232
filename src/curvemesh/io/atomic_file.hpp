#pragma once
// Output files are written to a temporary name beside the target and renamed
// into place on commit(), so a failure never leaves a partial file.
#include <cstdio>
#include <string>
#include <string_view>

namespace cm::io {

class AtomicFile {
 public:
  /// Opens "<path>.tmp-<pid>" for binary writing; throws std::runtime_error
  /// naming the path if it cannot be created.
  explicit AtomicFile(std::string path);
  /// Removes the temporary file unless commit() succeeded.
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void write(const void* data, std::size_t bytes);
  void write(std::string_view text) { write(text.data(), text.size()); }
  /// Flushes, closes and renames onto the target path; throws on failure.
  void commit();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::string tmp_path_;
  std::FILE* file_ = nullptr;
  bool committed_ = false;
};

/// Reads a whole file into memory; throws InputError (line -1) if it cannot
/// be opened or read.
std::string read_file_bytes(const std::string& path);

}  // namespace cm::io
