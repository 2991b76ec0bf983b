// `refit`: the command line. Every error reaches the user as one line on stderr
// and a non-zero exit; commands write their outputs atomically.
#include "command.hpp"

#include <refit/core/error.hpp>
#include <refit/core/heap.hpp>
#include <refit/io/atomic_file.hpp>
#include <refit/io/mapped_file.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

namespace refit::cli {
namespace {
constexpr const char* kHugePagesTunable = "glibc.malloc.hugetlb=1";
}

bool huge_pages_requested() {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  return tunables && std::strstr(tunables, kHugePagesTunable);
}

std::vector<CommandInfo>& registry() {
  static std::vector<CommandInfo> commands;
  return commands;
}
}  // namespace refit::cli

namespace {

// Large buffers on transparent huge pages, when REFIT_HUGE_PAGES=1 asks for it.
// Off by default: on a virtual machine that hands free memory back to its host
// (virtio-balloon free page reporting, as on the machine this project is measured
// on), free 2 MB blocks go back a few seconds after they are freed, so a huge
// page is almost always memory the host must fault in again: the dense 1M dress
// spent 6.6 s of system time with huge pages against 0.7 s without (wall 11.2
// against 7.5 s; bench/README.md, "Huge pages off by default"). On a machine
// whose 4 KB faults are the expensive part they still help (10.1 -> 7.2 s there),
// which is why the switch stays. glibc takes it only from the environment at
// start, so the command sets it and runs itself again; a tool tracing this
// process (valgrind) would lose it across the exec, so under valgrind nothing is done.
void run_on_huge_pages(char** argv) {
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  if (tunables && std::strstr(tunables, "glibc.malloc.hugetlb")) return;  // set already (by us or the user)
  const char* asked = std::getenv("REFIT_HUGE_PAGES");
  if (!asked || std::strcmp(asked, "1") != 0) return;
  const char* preload = std::getenv("LD_PRELOAD");
  if (preload && std::strstr(preload, "vgpreload")) return;
  const std::string tunable = refit::cli::kHugePagesTunable;
  const std::string value = tunables && *tunables ? std::string(tunables) + ":" + tunable : tunable;
  if (setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  execv("/proc/self/exe", argv);  // returns only if it failed: then run on as we are
  unsetenv("GLIBC_TUNABLES");
  if (tunables) setenv("GLIBC_TUNABLES", tunables, 1);
}

}  // namespace

int main(int argc, char** argv) {
  run_on_huge_pages(argv);
  refit::keep_freed_memory();
  using namespace refit::cli;
  CLI::App app{"refit: resize 3D garments to new bodies while keeping their designed shape"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "refit 0.1.0");
  app.footer("Exit codes: 0 ok, 1 bad input, 2 usage, 3 out of resources, 4 some bodies of a batch failed.");
  // A usage error is one line like every other error (not CLI11's two).
  app.failure_message([](const CLI::App*, const CLI::Error& e) {
    return std::string("refit: error: ") + e.what() + " (see --help)\n";
  });
  auto& commands = registry();
  std::sort(commands.begin(), commands.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  std::vector<std::pair<CLI::App*, std::function<int()>>> actions;
  // CLI11 reads "nan" and "inf" as numbers and its ranges let NaN through: every
  // number option of every command takes finite values only.
  const CLI::Validator finite(
      [](std::string& value) {
        char* end = nullptr;
        const double v = std::strtod(value.c_str(), &end);
        return end != value.c_str() && !std::isfinite(v) ? "Value " + value + " is not a finite number" : std::string();
      },
      "");
  for (auto& c : commands) {
    CLI::App* sub = app.add_subcommand(c.name, c.description);
    actions.emplace_back(sub, c.setup(*sub));
    for (CLI::Option* option : sub->get_options())
      if (option->get_type_name().rfind("FLOAT", 0) == 0) option->transform(finite);  // first: before its range
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help/--version exit 0; every usage error exits 2 (not CLI11's own 104/105/...).
    return app.exit(e) == 0 ? 0 : 2;
  }
  refit::remove_temporaries_on_signal();
  refit::map_input_files();
  try {
    for (auto& [sub, action] : actions)
      if (sub->parsed()) return action();
  } catch (const refit::ResourceError& e) {
    std::fprintf(stderr, "refit: error: %s\n", e.what());
    return 3;
  } catch (const refit::Error& e) {
    std::fprintf(stderr, "refit: error: %s\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "refit: error: out of memory\n");
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "refit: internal error: %s\n", e.what());
    return 2;
  }
  return 0;
}
