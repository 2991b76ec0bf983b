#include "manifest.hpp"

#include <refit/core/error.hpp>

#include <csv.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <set>

namespace refit::cli {
namespace {

namespace fs = std::filesystem;

std::string trimmed(std::string s) {
  auto space = [](unsigned char c) { return std::isspace(c) != 0; };
  s.erase(s.begin(), std::find_if_not(s.begin(), s.end(), space));
  s.erase(std::find_if_not(s.rbegin(), s.rend(), space).base(), s.end());
  return s;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// libcsv calls these for each field and at the end of each row.
struct Rows {
  std::vector<std::string> fields;
  std::vector<std::pair<std::vector<std::string>, std::size_t>> rows;  // fields, line
  std::size_t line = 0;
};

void on_field(void* data, std::size_t size, void* rows) {
  static_cast<Rows*>(rows)->fields.push_back(trimmed(std::string(static_cast<const char*>(data), size)));
}

void on_row(int, void* data) {
  auto* r = static_cast<Rows*>(data);
  r->rows.emplace_back(std::move(r->fields), r->line);
  r->fields.clear();
}

std::string resolved(const std::string& path, const fs::path& folder) {
  const fs::path p(path);
  return p.is_absolute() || folder.empty() ? path : (folder / p).string();
}

}  // namespace

std::vector<ManifestRow> read_manifest(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw input_error(path, "cannot open the manifest");
  csv_parser parser;
  if (csv_init(&parser, CSV_APPEND_NULL) != 0) throw input_error(path, "cannot start the CSV parser");
  Rows rows;
  std::string text;
  // A line at a time, so each row knows the line it ends on.
  while (std::getline(in, text)) {
    ++rows.line;
    text += '\n';
    if (csv_parse(&parser, text.data(), text.size(), on_field, on_row, &rows) != text.size()) {
      const std::string why = csv_strerror(csv_error(&parser));
      csv_free(&parser);
      throw input_error(path, why, rows.line);
    }
  }
  csv_fini(&parser, on_field, on_row, &rows);
  csv_free(&parser);

  const fs::path folder = fs::path(path).parent_path();
  std::vector<ManifestRow> out;
  std::set<std::string> outputs;
  for (const auto& [fields, line] : rows.rows) {
    if (fields.empty() || (fields.size() == 1 && fields[0].empty())) continue;
    if (!fields[0].empty() && fields[0][0] == '#') continue;
    if (out.empty() && fields.size() >= 2 && lower(fields[0]) == "body" && lower(fields[1]) == "output") continue;
    if (fields.size() < 2 || fields.size() > 3)
      throw input_error(path, "expected body,output[,name], found " + std::to_string(fields.size()) + " fields", line);
    if (fields[0].empty() || fields[1].empty()) throw input_error(path, "empty body or output file name", line);
    ManifestRow r;
    r.body = resolved(fields[0], folder);
    r.output = resolved(fields[1], folder);
    r.name = fields.size() == 3 && !fields[2].empty() ? fields[2] : fs::path(fields[0]).stem().string();
    r.line = line;
    if (!outputs.insert(fs::path(r.output).lexically_normal().string()).second)
      throw input_error(path, "output " + fields[1] + " appears twice", line);
    out.push_back(std::move(r));
  }
  if (out.empty()) throw input_error(path, "the manifest lists no bodies");
  return out;
}

std::string check_shard(const std::string& text) {
  const auto slash = text.find('/');
  std::size_t i = 0, n = 0;
  const char* end = text.data() + text.size();
  if (slash == std::string::npos || std::from_chars(text.data(), text.data() + slash, i).ptr != text.data() + slash ||
      std::from_chars(text.data() + slash + 1, end, n).ptr != end || slash == 0 || slash + 1 == text.size())
    return "'" + text + "' is not I/N (e.g. 0/4)";
  if (n == 0 || i >= n) return "'" + text + "': I must be in 0 to N-1";
  return {};
}

Shard parse_shard(const std::string& text) {
  if (const std::string why = check_shard(text); !why.empty()) throw Error("--shard: " + why);
  const auto slash = text.find('/');
  Shard s;
  std::from_chars(text.data(), text.data() + slash, s.index);
  std::from_chars(text.data() + slash + 1, text.data() + text.size(), s.count);
  return s;
}

std::vector<ManifestRow> shard_rows(const std::vector<ManifestRow>& rows, Shard shard) {
  const std::size_t m = rows.size();
  const std::size_t first = shard.index * m / shard.count, last = (shard.index + 1) * m / shard.count;
  return {rows.begin() + static_cast<std::ptrdiff_t>(first), rows.begin() + static_cast<std::ptrdiff_t>(last)};
}

}  // namespace refit::cli
