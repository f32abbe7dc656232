#pragma once
// The JSON reports of the commands (--json FILE): indented, newline-ended,
// written atomically so a failed run never leaves half a report.
#include <string>

#include <nlohmann/json.hpp>

#include "curvemesh/io/atomic_file.hpp"

namespace cm::cli {

inline void write_json(const nlohmann::json& j, const std::string& path) {
  io::AtomicFile out(path);
  out.write(j.dump(2));
  out.write("\n");
  out.commit();
}

}  // namespace cm::cli
