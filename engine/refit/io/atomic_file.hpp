#pragma once
// Output files appear whole or not at all: write to a temporary file beside the
// target, then rename over it. On any exception the temporary is removed.
#include <functional>
#include <ostream>
#include <string>

namespace refit {

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace refit
