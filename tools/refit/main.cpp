// `refit`: the command line. Every error reaches the user as one line on stderr
// and a non-zero exit; commands write their outputs atomically.
#include "command.hpp"

#include <refit/core/error.hpp>
#include <refit/io/atomic_file.hpp>

#include <algorithm>
#include <cstdio>
#include <exception>

namespace refit::cli {
std::vector<CommandInfo>& registry() {
  static std::vector<CommandInfo> commands;
  return commands;
}
}  // namespace refit::cli

int main(int argc, char** argv) {
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
  for (auto& c : commands) {
    CLI::App* sub = app.add_subcommand(c.name, c.description);
    actions.emplace_back(sub, c.setup(*sub));
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help/--version exit 0; every usage error exits 2 (not CLI11's own 104/105/...).
    return app.exit(e) == 0 ? 0 : 2;
  }
  refit::remove_temporaries_on_signal();
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
