// SVG output of a sheet; see svg.hpp.
#include <refit/patterns/svg.hpp>

#include <refit/core/error.hpp>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

namespace refit {
namespace {

std::string escaped(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", x);
  return buf;
}

}  // namespace

std::string sheet_svg(const Sheet& sheet, double cm_per_unit, const std::string& units) {
  if (units != "cm" && units != "mm") throw Error("svg: units must be cm or mm, not '" + units + "'");
  const double scale = cm_per_unit * (units == "mm" ? 10.0 : 1.0);  // output units per garment unit
  // The drawing's extent: the sheet and anything drawn beyond it (a legend), plus a margin.
  Eigen::Vector2d lo(0, 0), hi(sheet.width, sheet.height);
  for (const SheetPath& p : sheet.paths)
    if (p.points.rows() > 0) {
      lo = lo.cwiseMin(p.points.colwise().minCoeff().transpose());
      hi = hi.cwiseMax(p.points.colwise().maxCoeff().transpose());
    }
  for (const SheetText& t : sheet.texts) {
    const double half = 0.3 * t.height * static_cast<double>(t.text.size());
    lo = lo.cwiseMin(t.at - Eigen::Vector2d(half, 0.3 * t.height));
    hi = hi.cwiseMax(t.at + Eigen::Vector2d(half, t.height));
  }
  const double pad = 0.02 * std::max(hi.x() - lo.x(), hi.y() - lo.y()) + 1e-9;
  lo.array() -= pad;
  hi.array() += pad;
  const double w = (hi.x() - lo.x()) * scale, h = (hi.y() - lo.y()) * scale;
  const auto X = [&](double x) { return num((x - lo.x()) * scale); };
  const auto Y = [&](double y) { return num((hi.y() - y) * scale); };
  const double stroke = 0.08 * (units == "mm" ? 10.0 : 1.0);  // 0.8 mm lines

  std::ostringstream out;
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << num(w) << units << "\" height=\"" << num(h) << units
      << "\" viewBox=\"0 0 " << num(w) << ' ' << num(h) << "\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  if (!sheet.fills.empty()) {
    out << "<g id=\"STRETCH\" stroke=\"none\">\n";
    for (const SheetFill& f : sheet.fills) {
      out << "<polygon fill=\"" << f.colour << "\" points=\"";
      for (const auto& c : f.corners) out << X(c.x()) << ',' << Y(c.y()) << ' ';
      out << "\"/>\n";
    }
    out << "</g>\n";
  }
  // Paths grouped by layer, in order of first appearance.
  std::vector<std::string> layers;
  for (const SheetPath& p : sheet.paths)
    if (std::find(layers.begin(), layers.end(), p.layer) == layers.end()) layers.push_back(p.layer);
  for (const std::string& layer : layers) {
    out << "<g id=\"" << escaped(layer) << "\" fill=\"none\" stroke-width=\"" << num(stroke)
        << "\" stroke-linejoin=\"round\">\n";
    for (const SheetPath& p : sheet.paths) {
      if (p.layer != layer || p.points.rows() < 2) continue;
      out << '<' << (p.closed ? "polygon" : "polyline") << " stroke=\"" << p.colour << '"';
      if (p.dashed) out << " stroke-dasharray=\"" << num(4 * stroke) << ' ' << num(2 * stroke) << '"';
      out << " points=\"";
      for (Eigen::Index i = 0; i < p.points.rows(); ++i) out << X(p.points(i, 0)) << ',' << Y(p.points(i, 1)) << ' ';
      out << "\"/>\n";
    }
    out << "</g>\n";
  }
  out << "<g id=\"" << kTextLayer << "\" font-family=\"sans-serif\" text-anchor=\"middle\" fill=\"#000000\">\n";
  for (const SheetText& t : sheet.texts)
    out << "<text x=\"" << X(t.at.x()) << "\" y=\"" << Y(t.at.y()) << "\" font-size=\"" << num(t.height * scale)
        << "\">" << escaped(t.text) << "</text>\n";
  out << "</g>\n</svg>\n";
  return out.str();
}

}  // namespace refit
