#include <refit/features/feature_file.hpp>

#include <refit/core/error.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

namespace refit {
namespace {

using json = nlohmann::json;

// Errors of one feature all start "FILE: feature 'NAME': ".
struct Ctx {
  const std::string& file;
  std::string who;
  double scale = 1.0;
  [[noreturn]] void fail(const std::string& problem) const { throw input_error(file, who + ": " + problem); }
};

void check_keys(const json& obj, std::initializer_list<const char*> allowed, const Ctx& c, const std::string& where) {
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    if (std::none_of(allowed.begin(), allowed.end(), [&](const char* k) { return it.key() == k; }))
      c.fail("unknown key '" + it.key() + "' in " + where);
  }
}

const json& require(const json& obj, const char* key, const Ctx& c, const std::string& where) {
  auto it = obj.find(key);
  if (it == obj.end()) c.fail("missing '" + std::string(key) + "' in " + where);
  return *it;
}

double number(const json& v, const Ctx& c, const std::string& what) {
  if (!v.is_number()) c.fail(what + " must be a number");
  const double d = v.get<double>();
  if (!std::isfinite(d)) c.fail(what + " is not finite");
  return d;
}

Vec3 vec3(const json& v, const Ctx& c, const std::string& what, bool is_position) {
  if (!v.is_array() || v.size() != 3) c.fail(what + " must be an array of 3 numbers");
  Vec3 p(number(v[0], c, what), number(v[1], c, what), number(v[2], c, what));
  // Directions have no units; positions are converted.
  return is_position ? Vec3(p * c.scale) : p;
}

// Counts are bounded so that a feature file cannot make a run take minutes
// (issue 17: 1e5 samples took 75 s, 1e4 fitted control points over 120 s).
std::size_t count(const json& v, const Ctx& c, const std::string& what, double most) {
  if (!v.is_number_integer() && !(v.is_number() && std::floor(v.get<double>()) == v.get<double>()))
    c.fail(what + " must be an integer");
  const double d = v.get<double>();
  if (d < 0 || d > most)
    c.fail(what + " is out of range (" + v.dump() + "; at most " + std::to_string(static_cast<long long>(most)) + ")");
  return static_cast<std::size_t>(d);
}

FeaturePlane parse_plane(const json& p, const Ctx& c) {
  if (!p.is_object()) c.fail("'plane' must be an object");
  check_keys(p, {"point", "normal", "segment", "view"}, c, "'plane'");
  const bool pn = p.contains("point") || p.contains("normal");
  const bool sv = p.contains("segment") || p.contains("view");
  if (pn && sv) c.fail("'plane' takes either point + normal or segment + view, not both");
  if (pn) {
    const Vec3 point = vec3(require(p, "point", c, "'plane'"), c, "plane point", true);
    const Vec3 normal = vec3(require(p, "normal", c, "'plane'"), c, "plane normal", false);
    if (!(normal.norm() > 1e-12)) c.fail("plane normal is zero");
    return FeaturePlane::from_point_normal(point, normal);
  }
  if (!sv) c.fail("'plane' needs point + normal or segment + view");
  const json& seg = require(p, "segment", c, "'plane'");
  if (!seg.is_array() || seg.size() != 2) c.fail("plane segment must be an array of 2 points");
  const Vec3 a = vec3(seg[0], c, "plane segment point", true);
  const Vec3 b = vec3(seg[1], c, "plane segment point", true);
  const Vec3 view = vec3(require(p, "view", c, "'plane'"), c, "plane view", false);
  const double len = (b - a).norm();
  if (!(len > 1e-9)) c.fail("plane segment has zero length");
  if (!(view.norm() > 1e-12)) c.fail("plane view direction is zero");
  const Vec3 n = (b - a).cross(view);
  if (!(n.norm() > 1e-9 * len * view.norm())) c.fail("plane view direction is parallel to the segment");
  // The segment swept along the view direction: the plane holds both.
  return FeaturePlane::from_point_normal(0.5 * (a + b), n);
}

FeatureSpec parse_feature(const json& f, std::size_t index, const Ctx& root) {
  Ctx c{root.file, "feature #" + std::to_string(index + 1), root.scale};
  if (!f.is_object()) c.fail("must be an object");
  FeatureSpec s;
  s.file = root.file;
  const json& name = require(f, "name", c, "the feature");
  if (!name.is_string() || name.get<std::string>().empty()) c.fail("'name' must be a non-empty string");
  s.name = name.get<std::string>();
  c.who = "feature '" + s.name + "'";
  check_keys(f, {"name", "plane", "curve", "samples", "role", "comment"}, c, "the feature");
  if (f.contains("role")) {
    const json& role = f["role"];
    if (!role.is_string() || (role.get<std::string>() != "shape" && role.get<std::string>() != "seam"))
      c.fail("'role' must be \"shape\" or \"seam\", got " + role.dump());
    s.role = role.get<std::string>() == "seam" ? CurveRole::seam : CurveRole::shape;
  }

  const json& curve = require(f, "curve", c, "the feature");
  if (!curve.is_object()) c.fail("'curve' must be an object");
  const json& kind = require(curve, "kind", c, "'curve'");
  if (!kind.is_string()) c.fail("curve 'kind' must be a string");
  const std::string k = kind.get<std::string>();
  if (k == "bspline") {
    s.kind = CurveKind::bspline;
  } else if (k == "slice") {
    s.kind = CurveKind::slice;
  } else if (k == "boundary") {
    s.kind = CurveKind::boundary;
  } else {
    c.fail("unknown curve kind '" + k + "' (expected bspline, slice or boundary)");
  }

  if (s.role == CurveRole::seam && s.kind == CurveKind::boundary)
    c.fail("a seam cannot be a boundary curve (the garment is already cut along its boundary)");
  if (f.contains("plane")) s.plane = parse_plane(f["plane"], c);
  else if (s.kind != CurveKind::boundary) c.fail("missing 'plane' (required for a " + k + " curve)");

  if (s.kind == CurveKind::bspline) {
    check_keys(curve, {"kind", "degree", "closed", "control_points"}, c, "'curve'");
    if (curve.contains("degree")) {
      const std::size_t d = count(curve["degree"], c, "curve 'degree'", 1e8);
      if (d < 1 || d > 15) c.fail("curve 'degree' must be between 1 and 15, got " + std::to_string(d));
      s.degree = static_cast<int>(d);
    }
    if (curve.contains("closed")) {
      if (!curve["closed"].is_boolean()) c.fail("curve 'closed' must be true or false");
      s.closed = curve["closed"].get<bool>();
    }
    const json& cp = require(curve, "control_points", c, "'curve'");
    if (!cp.is_array()) c.fail("curve 'control_points' must be an array of points");
    if (cp.size() < static_cast<std::size_t>(s.degree) + 1)
      c.fail("a degree " + std::to_string(s.degree) + " B-spline needs at least " + std::to_string(s.degree + 1) +
             " control points, got " + std::to_string(cp.size()));
    s.control_points.resize(static_cast<Eigen::Index>(cp.size()), 3);
    for (std::size_t i = 0; i < cp.size(); ++i)
      s.control_points.row(static_cast<Eigen::Index>(i)) =
          vec3(cp[i], c, "control point " + std::to_string(i + 1), true).transpose();
    // Projected onto the plane, the control polygon must still span a curve.
    Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
    for (Eigen::Index i = 0; i < s.control_points.rows(); ++i) {
      const Vec3 q = s.plane->project(row3(s.control_points, static_cast<Index>(i)));
      lo = lo.cwiseMin(q);
      hi = hi.cwiseMax(q);
    }
    if (!((hi - lo).norm() > 0.0)) c.fail("the control points all project to one point of the plane");
  } else if (s.kind == CurveKind::slice) {
    check_keys(curve, {"kind", "near", "from", "to", "control_points"}, c, "'curve'");
    s.near = vec3(require(curve, "near", c, "'curve'"), c, "curve 'near'", true);
    if (curve.contains("from")) s.from = vec3(curve["from"], c, "curve 'from'", true);
    if (curve.contains("to")) s.to = vec3(curve["to"], c, "curve 'to'", true);
    if (s.from.has_value() != s.to.has_value()) c.fail("curve 'from' and 'to' must be given together");
    if (s.from && s.to && (*s.from - *s.to).norm() == 0.0) c.fail("curve 'from' and 'to' are the same point");
    if (curve.contains("control_points")) {
      if (curve["control_points"].is_array())
        c.fail("a slice's 'control_points' is the number of control points of its fitted B-spline, not a list");
      s.fit_control_points = count(curve["control_points"], c, "curve 'control_points'", kMaxFitControlPoints);
    }
    if (s.fit_control_points < static_cast<std::size_t>(s.degree) + 1)
      c.fail("a slice needs at least " + std::to_string(s.degree + 1) + " control points, got " +
             std::to_string(s.fit_control_points));
  } else {
    check_keys(curve, {"kind", "near"}, c, "'curve'");
    s.near = vec3(require(curve, "near", c, "'curve'"), c, "curve 'near'", true);
    s.closed = true;
  }

  s.samples = count(require(f, "samples", c, "the feature"), c, "'samples'", kMaxSamples);
  // A slice's closedness is known only after cutting: check the open minimum
  // then (build_feature_curves) and the closed minimum now.
  const bool closed_now = s.kind == CurveKind::slice ? true : s.closed;
  if (s.samples < min_samples(closed_now))
    c.fail(std::string("'samples' is ") + std::to_string(s.samples) + ": " + (closed_now ? "a closed" : "an open") +
           " curve needs at least " + std::to_string(min_samples(closed_now)) + " samples");
  return s;
}

std::size_t line_of(const std::string& text, std::size_t byte) {
  byte = std::min(byte, text.size());
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<long>(byte), '\n'));
}

}  // namespace

const char* to_string(CurveKind kind) {
  switch (kind) {
    case CurveKind::bspline: return "bspline";
    case CurveKind::slice: return "slice";
    case CurveKind::boundary: return "boundary";
  }
  return "?";
}

const char* to_string(CurveRole role) { return role == CurveRole::seam ? "seam" : "shape"; }

double metres_per_unit(const std::string& units, const std::string& file) {
  if (units == "cm") return 0.01;
  if (units == "mm") return 0.001;
  if (units == "m") return 1.0;
  if (units == "in") return 0.0254;
  throw input_error(file, "unknown units '" + units + "' (expected cm, mm, m or in)");
}

std::vector<FeatureSpec> parse_feature_json(const std::string& text, const std::string& file,
                                            const std::string& garment_units) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    std::string what = e.what();
    // nlohmann's message starts with "[json.exception.parse_error.101] parse error at line L, column C: ".
    const auto colon = what.find(": ", what.find("parse error"));
    throw input_error(file, "invalid JSON: " + (colon == std::string::npos ? what : what.substr(colon + 2)),
                      line_of(text, e.byte == 0 ? 0 : e.byte - 1));
  } catch (const json::exception& e) {
    // e.g. a number too large for a double ("1e999").
    std::string what = e.what();
    const auto close = what.find("] ");
    throw input_error(file, "invalid JSON: " + (close == std::string::npos ? what : what.substr(close + 2)));
  }
  Ctx c{file, "feature file"};
  if (!root.is_object()) throw input_error(file, "the feature file must be a JSON object with a 'features' array");
  for (auto it = root.begin(); it != root.end(); ++it)
    if (it.key() != "units" && it.key() != "features" && it.key() != "comment")
      throw input_error(file, "unknown key '" + it.key() + "' (expected 'units' and 'features')");
  const double garment_m = metres_per_unit(garment_units, file);
  double file_m = garment_m;
  if (root.contains("units")) {
    if (!root["units"].is_string()) throw input_error(file, "'units' must be a string (cm, mm, m or in)");
    file_m = metres_per_unit(root["units"].get<std::string>(), file);
  }
  c.scale = file_m / garment_m;
  if (!root.contains("features")) throw input_error(file, "missing 'features' array");
  const json& features = root["features"];
  if (!features.is_array()) throw input_error(file, "'features' must be an array");
  if (features.empty()) throw input_error(file, "'features' is empty");
  std::vector<FeatureSpec> out;
  std::set<std::string> names;
  for (std::size_t i = 0; i < features.size(); ++i) {
    out.push_back(parse_feature(features[i], i, c));
    if (!names.insert(out.back().name).second)
      throw input_error(file, "feature '" + out.back().name + "': the name is used twice");
  }
  return out;
}

std::vector<FeatureSpec> features_with_role(const std::vector<FeatureSpec>& specs, CurveRole role) {
  std::vector<FeatureSpec> out;
  std::copy_if(specs.begin(), specs.end(), std::back_inserter(out), [&](const FeatureSpec& s) { return s.role == role; });
  return out;
}

std::vector<FeatureSpec> read_feature_file(const std::string& path, const std::string& garment_units) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw input_error(path, "cannot open the feature file");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw input_error(path, "cannot read the feature file");
  return parse_feature_json(ss.str(), path, garment_units);
}

}  // namespace refit
