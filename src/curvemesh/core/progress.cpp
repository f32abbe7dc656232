#include "curvemesh/core/progress.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>

namespace cm {

Progress::Progress(std::string label, std::int64_t total)
    : label_(std::move(label)),
      total_(total > 0 ? total : 1),
      enabled_(isatty(STDERR_FILENO) != 0 && std::getenv("CI") == nullptr) {}

Progress::~Progress() { finish(); }

void Progress::update(std::int64_t done) {
  if (!enabled_ || done < next_draw_) return;
  next_draw_ = done + total_ / 100 + 1;
  const int width = 40;
  const int filled = static_cast<int>(width * done / total_);
  std::fprintf(stderr, "\r%s [", label_.c_str());
  for (int i = 0; i < width; ++i) std::fputc(i < filled ? '#' : ' ', stderr);
  std::fprintf(stderr, "] %3d%%", static_cast<int>(100 * done / total_));
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || finished_) return;
  finished_ = true;
  update(total_);
  std::fputc('\n', stderr);
}

}  // namespace cm
