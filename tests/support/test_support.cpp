#include "support/test_support.hpp"

#include <atomic>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace refit::test {

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  std::random_device rd;
  path_ = std::filesystem::temp_directory_path() /
          ("refit-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "-" +
           std::to_string(rd() % 100000));
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

namespace {
constexpr const char* kDeathTestFolder = "REFIT_TEST_DEATH_FOLDER";
}

DeathTestFolder::DeathTestFolder() {
  if (const char* inherited = std::getenv(kDeathTestFolder)) {
    path_ = inherited;
    return;
  }
  own_ = std::make_unique<TempDir>();
  path_ = own_->path();
  ::setenv(kDeathTestFolder, path_.c_str(), 1);
}

DeathTestFolder::~DeathTestFolder() {
  if (own_) ::unsetenv(kDeathTestFolder);
}

std::size_t folder_entries(const std::filesystem::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++n;
  return n;
}

std::string shared_data_dir() {
  const std::filesystem::path dir(REFIT_SHARED_DATA);
  if (std::filesystem::exists(dir / "bodies" / "A_female.obj")) return dir.string();
  return {};
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

CommandResult run_shell(const std::string& command) {
  TempDir dir;
  const std::string out = dir.file("stdout"), err = dir.file("stderr");
  const std::string cmd = command + " >'" + out + "' 2>'" + err + "' </dev/null";
  const int status = std::system(cmd.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_text(out);
  r.err = read_text(err);
  return r;
}

CommandResult run_cli(const std::string& args) { return run_shell(std::string("'") + REFIT_CLI_PATH + "' " + args); }

}  // namespace refit::test
