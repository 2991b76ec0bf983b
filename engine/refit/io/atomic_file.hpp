#pragma once
// Output files appear whole or not at all: write to a temporary file beside the
// target, then rename over it. On any exception the temporary is removed.
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace refit {

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// The same for text already formatted in parts, written one after another: each
/// part goes straight to its offset (pwrite, parts in parallel) instead of
/// through one buffered stream. Throws refit::Error naming `path` when the file
/// cannot be written.
void write_parts_atomically(const std::string& path, const std::vector<std::string>& parts);

}  // namespace refit
