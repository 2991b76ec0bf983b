#pragma once
// JSON reports are written like every other output: whole or not at all.
#include <refit/io/atomic_file.hpp>

#include <nlohmann/json.hpp>

namespace refit::cli {

inline void write_json_report(const std::string& path, const nlohmann::json& doc) {
  write_file_atomically(path, [&](std::ostream& out) { out << doc.dump(2) << '\n'; });
}

}  // namespace refit::cli
