#pragma once
// Shared helpers for the test suites: temporary folders, the shared data folder,
// running the command line.
#include <filesystem>
#include <memory>
#include <string>

namespace refit::test {

/// A fresh empty folder under the system temp dir, removed on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

/// The folder of a death test, the same in its child: in the "threadsafe" style
/// the child runs the test again from its start in a process of its own, where
/// a TempDir would be another folder, so the parent's goes to it in the
/// environment. Made in the parent (and removed there); the child's is the parent's.
class DeathTestFolder {
 public:
  DeathTestFolder();
  ~DeathTestFolder();
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::unique_ptr<TempDir> own_;  // the parent's
  std::filesystem::path path_;
};

/// How many entries the folder holds (files and folders, not recursing).
std::size_t folder_entries(const std::filesystem::path& dir);

/// ../shared/data, or "" when absent (tests then GTEST_SKIP with a clear message).
std::string shared_data_dir();

struct CommandResult {
  int exit_code = 0;
  std::string out;  // stdout
  std::string err;  // stderr
};
/// Runs `refit <args>` (the built CLI) through the shell.
CommandResult run_cli(const std::string& args);
/// Runs a shell command, capturing its output.
CommandResult run_shell(const std::string& command);

std::string read_text(const std::string& path);
void write_text(const std::string& path, const std::string& text);

}  // namespace refit::test
