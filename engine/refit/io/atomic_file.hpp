#pragma once
// Output files appear whole or not at all: write to a temporary file beside the
// target, then rename over it. On any exception the temporary is removed.
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace refit {

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

/// Appends part k of a text to `out` (an emptied buffer).
using PartFormatter = std::function<void(std::size_t k, std::string& out)>;

/// The same for a text made of `count` parts, written one after another. Parts
/// are formatted in parallel a batch at a time into buffers reused from batch to
/// batch, and each goes straight to its offset (pwrite) instead of through one
/// buffered stream: the whole text never sits in memory (a 4M-vertex garment is
/// 364 MB of it). Throws refit::Error naming `path` when the file cannot be
/// written; an exception from `format` propagates; either way nothing is left.
void write_parts_atomically(const std::string& path, std::size_t count, const PartFormatter& format);

}  // namespace refit
