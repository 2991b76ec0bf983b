// Grading: two patterns of one cut compared piece by piece; see grading.hpp.
#include <refit/patterns/grading.hpp>

#include <refit/core/error.hpp>
#include <refit/patterns/layout.hpp>
#include <refit/patterns/lengths.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace refit {
namespace {

Eigen::Vector2d box_size(const Points2& uv) { return (uv.colwise().maxCoeff() - uv.colwise().minCoeff()).transpose(); }

double loops_length(const Panel& panel, const Points2& uv) {
  double len = 0;
  for (const auto& loop : panel.loops) len += indexed_length(uv, loop, true);
  return len;
}

double signed_area(const Panel& panel, const Points2& uv) {
  double a = 0;
  for (const Triangle& t : panel.triangles) {
    const Eigen::Vector2d p = uv.row(t[1]) - uv.row(t[0]), q = uv.row(t[2]) - uv.row(t[0]);
    a += 0.5 * (p.x() * q.y() - p.y() * q.x());
  }
  return a;
}

// The best similarity (rotation, uniform scale unless `rigid`, translation; no
// reflection) taking the rows of `from` onto those of `to`, in closed form: in
// the complex plane it is w = a z + b.
Points2 fitted(const Points2& from, const Points2& to, bool rigid) {
  const Eigen::RowVector2d cf = from.colwise().mean(), ct = to.colwise().mean();
  double re = 0, im = 0, norm = 0;
  for (Eigen::Index i = 0; i < from.rows(); ++i) {
    const Eigen::RowVector2d z = from.row(i) - cf, w = to.row(i) - ct;
    re += z.x() * w.x() + z.y() * w.y();  // conj(z) w
    im += z.x() * w.y() - z.y() * w.x();
    norm += z.squaredNorm();
  }
  if (!(norm > 0)) return Points2(Points2::Zero(from.rows(), 2).rowwise() + ct);
  double a = re / norm, b = im / norm;
  if (rigid) {
    const double m = std::hypot(a, b);
    a = m > 0 ? a / m : 1.0, b = m > 0 ? b / m : 0.0;
  }
  Eigen::Matrix2d A;
  A << a, -b, b, a;
  return ((from.rowwise() - cf) * A.transpose()).rowwise() + ct;
}

std::string signed_percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%+.1f %%", 100 * x);
  return buf;
}

}  // namespace

double shape_deviation_2d(const Points2& line, const Points2& original, bool closed) {
  if (line.rows() != original.rows())
    throw Error("straightness: lines have different sample counts (" + std::to_string(line.rows()) + " and " +
                std::to_string(original.rows()) + ")");
  if (line.rows() < 2) throw Error("straightness: need at least 2 samples");
  const double length = rows_length(original, closed);
  if (!(length > 0)) throw Error("straightness: the original line has zero length");
  return std::sqrt((fitted(original, line, false) - line).rowwise().squaredNorm().mean()) / length;
}

Grading grade_pattern(const Garment& g, const PatternCut& cut, const Pattern& original, const Pattern& resized) {
  Grading out;
  const auto& panels = cut.panels.panels;
  if (original.pieces.size() != panels.size() || resized.pieces.size() != panels.size())
    throw Error("grading: the patterns come from different cuts");
  out.pieces.resize(panels.size());
  double sum = 0;
  for (std::size_t k = 0; k < panels.size(); ++k) {
    PieceGrading& pg = out.pieces[k];
    pg.panel = panels[k].name;
    const PatternPiece &a = original.pieces[k], &b = resized.pieces[k];
    if (!a.flattened || !b.flattened) continue;
    pg.graded = true;
    pg.area_change = signed_area(panels[k], b.uv) / signed_area(panels[k], a.uv) - 1;
    pg.perimeter_change = loops_length(panels[k], b.uv) / loops_length(panels[k], a.uv) - 1;
    const Eigen::Vector2d sa = box_size(a.uv), sb = box_size(b.uv);
    pg.width_change = sb.x() / sa.x() - 1;
    pg.height_change = sb.y() / sa.y() - 1;
    for (const FeatureLine& line : cut.lines) {
      if (line.panel != k) continue;
      const Points2 pa = line_points(line, cut.panels, g, a.uv), pb = line_points(line, cut.panels, g, b.uv);
      LineGrading lg;
      lg.name = line.name;
      lg.length_original = rows_length(pa, line.closed);
      lg.length = rows_length(pb, line.closed);
      if (!(lg.length_original > 0)) continue;
      lg.deviation = shape_deviation_2d(pb, pa, line.closed);
      sum += lg.deviation;
      out.deviation_max = std::max(out.deviation_max, lg.deviation);
      ++out.lines;
      pg.lines.push_back(lg);
    }
  }
  out.deviation_mean = out.lines > 0 ? sum / static_cast<double>(out.lines) : 0.0;
  return out;
}

Sheet grading_sheet(const Garment& g, const PatternCut& cut, const Pattern& original, const Pattern& resized,
                    const Grading& grading, double margin) {
  const auto& panels = cut.panels.panels;
  const double text = std::max(original.width, original.height) / 60.0;
  // Each graded pair: the original at its place, the resized piece turned onto it (best rotation), beside it.
  struct Pair {
    std::size_t k;
    Points2 a, b;
  };
  std::vector<Pair> pairs;
  std::vector<Box> boxes;
  for (std::size_t k = 0; k < panels.size(); ++k) {
    if (!grading.pieces[k].graded) continue;
    Points2 a = original.pieces[k].uv, b = resized.pieces[k].uv;
    b = fitted(b, a, true);
    a.rowwise() -= a.colwise().minCoeff();
    b.rowwise() -= b.colwise().minCoeff();
    const Eigen::Vector2d sa = box_size(a), sb = box_size(b);
    b.col(0).array() += sa.x() + margin;
    // Room for the label under the pair.
    a.col(1).array() += 3 * text;
    b.col(1).array() += 3 * text;
    boxes.push_back({sa.x() + margin + sb.x(), std::max(sa.y(), sb.y()) + 3 * text});
    pairs.push_back({k, std::move(a), std::move(b)});
  }
  const Packing packing = pack_boxes(boxes, margin);
  Sheet sheet;
  sheet.width = packing.width;
  sheet.height = packing.height;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    Pair& p = pairs[i];
    p.a.rowwise() += packing.corner[i].transpose();
    p.b.rowwise() += packing.corner[i].transpose();
    add_piece(sheet, g, cut, p.k, p.a, "#8c8c8c", true);
    add_piece(sheet, g, cut, p.k, p.b, "#000000");
    const PieceGrading& pg = grading.pieces[p.k];
    const Eigen::Vector2d at(packing.corner[i].x() + 0.5 * boxes[i].width, packing.corner[i].y() + text);
    sheet.texts.push_back({at, panels[p.k].name + ": area " + signed_percent(pg.area_change) + ", perimeter " +
                                   signed_percent(pg.perimeter_change),
                           text, kTextLayer});
  }
  return sheet;
}

nlohmann::json grading_report(const Grading& grading) {
  nlohmann::json pieces = nlohmann::json::array();
  for (const PieceGrading& pg : grading.pieces) {
    nlohmann::json p = {{"name", pg.panel}, {"graded", pg.graded}};
    if (pg.graded) {
      p["area_change"] = pg.area_change;
      p["perimeter_change"] = pg.perimeter_change;
      p["width_change"] = pg.width_change;
      p["height_change"] = pg.height_change;
      nlohmann::json lines = nlohmann::json::array();
      for (const LineGrading& l : pg.lines)
        lines.push_back({{"name", l.name}, {"length_original", l.length_original}, {"length", l.length},
                         {"straightness", l.deviation}});
      p["feature_lines"] = lines;
    }
    pieces.push_back(p);
  }
  return {{"panels", pieces},
          {"feature_lines", grading.lines},
          {"straightness_mean", grading.deviation_mean},
          {"straightness_max", grading.deviation_max}};
}

}  // namespace refit
