#pragma once
#include <cstdint>
#include <string>

namespace cm {

/// A progress bar on stderr, drawn only when stderr is a terminal and the
/// environment variable CI is unset, so logs stay clean. Cheap to update in a
/// loop: it redraws at most every 1% of the work.
class Progress {
 public:
  Progress(std::string label, std::int64_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void update(std::int64_t done);
  void finish();

 private:
  std::string label_;
  std::int64_t total_;
  std::int64_t next_draw_ = 0;
  bool enabled_;
  bool finished_ = false;
};

}  // namespace cm
