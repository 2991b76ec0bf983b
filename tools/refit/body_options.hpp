#pragma once
// Mannequin parameters as command-line options, shared by `generate` and `demo`.
#include "mannequin/mannequin.hpp"

#include <CLI/CLI.hpp>

#include <string>

namespace refit::cli {

inline void add_body_options(CLI::App& app, mannequin::BodyParams& p, const std::string& prefix = "") {
  app.add_option("--" + prefix + "height", p.height, "Height in cm")->capture_default_str();
  app.add_option("--" + prefix + "bust", p.bust, "Bust girth in cm")->capture_default_str();
  app.add_option("--" + prefix + "waist", p.waist, "Waist girth in cm")->capture_default_str();
  app.add_option("--" + prefix + "hip", p.hip, "Hip girth in cm")->capture_default_str();
  app.add_option("--" + prefix + "belly", p.belly, "Forward belly bulge at the navel in cm")->capture_default_str();
  app.add_option("--" + prefix + "shoulder", p.shoulder, "Shoulder width in cm")->capture_default_str();
}

}  // namespace refit::cli
