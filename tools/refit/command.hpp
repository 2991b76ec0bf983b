#pragma once
// Each `refit <command>` lives in its own cmd_<name>.cpp and registers itself
// here, so commands stay independent and CLI11 is compiled in few places.
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

namespace refit::cli {

/// Adds the subcommand's options to `app`; returns the action to run when chosen
/// (it returns the process exit code).
using CommandSetup = std::function<std::function<int()>(CLI::App& app)>;

struct CommandInfo {
  std::string name;
  std::string description;
  CommandSetup setup;
};

std::vector<CommandInfo>& registry();

struct Register {
  Register(std::string name, std::string description, CommandSetup setup) {
    registry().push_back({std::move(name), std::move(description), std::move(setup)});
  }
};

/// Whether this process runs with glibc's malloc asked for transparent huge
/// pages (main.cpp sets it up; the report's `huge_pages`).
bool huge_pages_requested();

}  // namespace refit::cli
