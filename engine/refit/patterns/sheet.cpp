// Pattern pieces drawn on a sheet; see sheet.hpp.
#include <refit/patterns/sheet.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace refit {
namespace {

Points2 rows_of(const Points2& uv, const std::vector<Index>& rows) {
  Points2 out(static_cast<Eigen::Index>(rows.size()), 2);
  for (std::size_t i = 0; i < rows.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = uv.row(rows[i]);
  return out;
}

// White (0) through yellow (half of `full`) to red (`full` and more).
std::string stretch_colour(double s, double full) {
  const double t = std::clamp(s / full, 0.0, 1.0);
  const int g = static_cast<int>(std::lround(255 * (t < 0.5 ? 1.0 : 2.0 * (1.0 - t))));
  const int b = static_cast<int>(std::lround(255 * std::max(0.0, 1.0 - 2.0 * t)));
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", 255, g, b);
  return buf;
}

}  // namespace

SheetText piece_label(const Panel& panel, const Points2& uv, const std::string& text, double height) {
  Eigen::Vector2d c(0, 0);
  double area = 0;
  for (const Triangle& t : panel.triangles) {
    const Eigen::Vector2d a = uv.row(t[0]).transpose(), b = uv.row(t[1]).transpose(), d = uv.row(t[2]).transpose();
    const double w = 0.5 * std::abs((b - a).x() * (d - a).y() - (b - a).y() * (d - a).x());
    c += w * (a + b + d) / 3.0;
    area += w;
  }
  c = area > 0 ? Eigen::Vector2d(c / area) : Eigen::Vector2d(uv.colwise().mean().transpose());
  const double box = (uv.colwise().maxCoeff() - uv.colwise().minCoeff()).maxCoeff();
  return {c, text, std::min(height, box / 10.0), kTextLayer};
}

void add_piece(Sheet& sheet, const Garment& g, const PatternCut& cut, std::size_t k, const Points2& uv,
               const std::string& colour, bool dashed) {
  const Panel& panel = cut.panels.panels[k];
  for (const auto& loop : panel.loops) sheet.paths.push_back({rows_of(uv, loop), true, kCutLayer, colour, dashed});
  for (const FeatureLine& line : cut.lines)
    if (line.panel == k)
      sheet.paths.push_back({line_points(line, cut.panels, g, uv), line.closed, kFeatureLayer, "#d0002a", dashed});
}

Sheet pattern_sheet(const Garment& g, const PatternCut& cut, const Pattern& pattern, bool stretch_map,
                    const std::string& colour) {
  Sheet sheet;
  sheet.width = pattern.width;
  sheet.height = pattern.height;
  const double text = std::max(pattern.width, pattern.height) / 60.0;
  for (std::size_t k = 0; k < pattern.pieces.size(); ++k) {
    const PatternPiece& piece = pattern.pieces[k];
    if (!piece.flattened) continue;
    const Panel& panel = cut.panels.panels[k];
    if (stretch_map)
      for (std::size_t t = 0, face = 0; t < panel.triangles.size(); ++t) {
        if (t > 0 && panel.triangle_face[t] != panel.triangle_face[t - 1]) ++face;  // a face's triangles are consecutive
        SheetFill f;
        for (int i = 0; i < 3; ++i) f.corners[i] = piece.uv.row(panel.triangles[t][i]).transpose();
        f.colour = stretch_colour(piece.face_stretch[face], 0.05);
        sheet.fills.push_back(f);
      }
    add_piece(sheet, g, cut, k, piece.uv, colour);
    SheetText label = piece_label(panel, piece.uv, panel.name, text);
    // The grain line: along +y through the label, a third of the piece's height.
    const double h = piece.uv.col(1).maxCoeff() - piece.uv.col(1).minCoeff();
    Points2 grain(2, 2);
    grain << label.at.x(), label.at.y() + label.height * 1.5, label.at.x(), label.at.y() + label.height * 1.5 + h / 3;
    sheet.paths.push_back({grain, false, kGrainLayer, "#0050c8", false});
    sheet.texts.push_back(std::move(label));
  }
  if (stretch_map)
    sheet.texts.push_back({Eigen::Vector2d(0.5 * sheet.width, -1.5 * text),
                           "stretch |log s|: white 0, yellow 2.5 %, red 5 % and more", text, kTextLayer});
  return sheet;
}

}  // namespace refit
