#include "curvemesh/io/atomic_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "curvemesh/core/error.hpp"

namespace cm::io {

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  tmp_path_ = fmt::format("{}.tmp-{}", path_, static_cast<long>(getpid()));
  file_ = std::fopen(tmp_path_.c_str(), "wb");
  if (!file_)
    throw std::runtime_error(fmt::format("{}: cannot create output file: {}", path_, std::strerror(errno)));
  // A large buffer matters for the multi-GB meshes: stdio's default is 4 KiB.
  std::setvbuf(file_, nullptr, _IOFBF, 1 << 20);
}

AtomicFile::~AtomicFile() {
  if (file_) std::fclose(file_);
  if (!committed_) std::remove(tmp_path_.c_str());
}

void AtomicFile::write(const void* data, std::size_t bytes) {
  if (bytes && std::fwrite(data, 1, bytes, file_) != bytes)
    throw std::runtime_error(fmt::format("{}: write failed: {}", path_, std::strerror(errno)));
}

void AtomicFile::commit() {
  const bool ok = std::fflush(file_) == 0 && std::fclose(file_) == 0;
  file_ = nullptr;
  if (!ok) throw std::runtime_error(fmt::format("{}: write failed: {}", path_, std::strerror(errno)));
  if (std::rename(tmp_path_.c_str(), path_.c_str()) != 0)
    throw std::runtime_error(fmt::format("{}: cannot rename temporary file: {}", path_, std::strerror(errno)));
  committed_ = true;
}

std::string read_file_bytes(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path, -1, -1, fmt::format("cannot open file: {}", std::strerror(errno)));
  // Size first, then one read: streaming through iterators costs as much as parsing.
  std::string data;
  if (std::fseek(f, 0, SEEK_END) == 0) {
    const long size = std::ftell(f);
    if (size > 0) data.resize(static_cast<std::size_t>(size));
    std::rewind(f);
  }
  const std::size_t got = data.empty() ? 0 : std::fread(data.data(), 1, data.size(), f);
  data.resize(got);
  // Pipes and special files report no size: read what comes.
  char buf[1 << 16];
  std::size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) data.append(buf, n);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw InputError(path, -1, -1, "read error");
  return data;
}

}  // namespace cm::io
