#pragma once
// A batch manifest (`refit resize --to-list`, and refit-batch in Python): a CSV
// file, one body per row: body file, output file, optional name. docs/cli.md
// has the rules; tools/python/refit/batch.py reads the same files the same way.
#include <cstddef>
#include <string>
#include <vector>

namespace refit::cli {

struct ManifestRow {
  std::string body, output, name;  // paths as given, relative ones resolved against the manifest's folder
  std::size_t line = 0;            // where the row ends in the manifest, for messages
};

/// Reads a manifest (RFC 4180 CSV through libcsv): fields trimmed, blank rows and
/// rows whose first field starts with '#' skipped, a first row "body,output[,name]"
/// taken as a header; the name defaults to the body file's stem. Throws
/// refit::Error naming the file and line for a row without 2 or 3 fields, an empty
/// field, two rows with one output, or a manifest with no rows.
std::vector<ManifestRow> read_manifest(const std::string& path);

/// "I/N" (0 <= I < N): the I-th of N contiguous slices, rows [I*M/N, (I+1)*M/N).
struct Shard {
  std::size_t index = 0, count = 1;
};

/// Parses "I/N"; returns an error message (empty when fine) for CLI11's check.
std::string check_shard(const std::string& text);
Shard parse_shard(const std::string& text);

/// The rows of `shard`: every row is in exactly one of the N shards.
std::vector<ManifestRow> shard_rows(const std::vector<ManifestRow>& rows, Shard shard);

}  // namespace refit::cli
