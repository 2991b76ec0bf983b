// Cut, flatten, measure and lay out a garment's pattern; see pattern.hpp.
#include <refit/patterns/pattern.hpp>

#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>
#include <refit/io/obj_attributes.hpp>
#include <refit/patterns/layout.hpp>
#include <refit/patterns/lengths.hpp>
#include <refit/patterns/measures.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>

namespace refit {
namespace {

// Garment vertices on a panel's boundary: where a seam curve may end.
std::vector<char> boundary_vertices(const PanelSet& set, std::size_t vertex_count) {
  std::vector<char> on(vertex_count, 0);
  for (const Panel& p : set.panels)
    for (const auto& loop : p.loops)
      for (Index v : loop) on[p.vertices[v]] = 1;
  return on;
}

void measure(const Garment& g, const PanelSet& set, std::size_t k, const Points& xyz, PatternPiece& piece) {
  PieceStretch ps = measure_piece(g, set, k, xyz, piece.uv);
  PieceMeasures& m = piece.measures;
  m.area_3d = ps.area_3d, m.area_2d = ps.area_2d, m.perimeter_3d = ps.perimeter_3d, m.perimeter_2d = ps.perimeter_2d;
  m.flipped = ps.flipped;
  m.stretch_p50 = percentile(ps.face, 50);
  m.stretch_p95 = percentile(ps.face, 95);
  m.stretch_max = ps.face.empty() ? 0.0 : *std::max_element(ps.face.begin(), ps.face.end());
  m.triangle_stretch_p95 = percentile(ps.triangle, 95);
  piece.face_stretch = std::move(ps.face);
}

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f %%", 100 * x);
  return buf;
}

}  // namespace

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  const double at = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(v.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(at));
  // The lo-th smallest and the next (a sort's v[lo] and v[lo + 1]), in linear time.
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(lo), v.end());
  const double low = v[lo];
  const double high = lo + 1 < v.size() ? *std::min_element(v.begin() + static_cast<std::ptrdiff_t>(lo) + 1, v.end()) : low;
  return low + (at - static_cast<double>(lo)) * (high - low);
}

PatternCut cut_pattern(const Garment& original, const std::vector<FeatureSpec>& specs, const std::string& file,
                       const std::string& features_file) {
  PatternCut cut;
  cut.file = file;
  const ObjFaceAttributes at = obj_face_attributes(original);
  cut.panels = cut_panels(original, at);
  const std::vector<FeatureSpec> seams = features_with_role(specs, CurveRole::seam);
  if (!seams.empty()) {
    const std::vector<FeatureCurve> curves = build_feature_curves(original, seams);
    cut.seam_paths = seam_paths(original, curves, boundary_vertices(cut.panels, original.vertex_count()), features_file);
    cut.panels = cut_panels(original, at, seam_path_edges(cut.seam_paths));
  }
  const std::vector<FeatureSpec> shapes = features_with_role(specs, CurveRole::shape);
  if (!shapes.empty()) cut.lines = bind_feature_lines(original, cut.panels, build_feature_curves(original, shapes));
  return cut;
}

std::vector<std::string> unflattenable_panels(const PatternCut& cut, bool skip) {
  std::vector<std::string> warnings;
  for (const Panel& p : cut.panels.panels) {
    if (p.problem.empty()) continue;
    const std::string what = "panel '" + p.name + "' (" + std::to_string(p.faces.size()) + " faces) cannot be flattened: " + p.problem;
    if (!skip) throw input_error(cut.file, what);
    warnings.push_back(what + "; left out");
  }
  return warnings;
}

Pattern flatten_pattern(const Garment& g, const PatternCut& cut, const Points& positions, const PatternOptions& options) {
  const std::vector<Panel>& panels = cut.panels.panels;
  if (positions.rows() != static_cast<Eigen::Index>(g.vertex_count()))
    throw Error("flatten: " + std::to_string(positions.rows()) + " positions for a garment of " +
                std::to_string(g.vertex_count()) + " vertices");
  Pattern out;
  out.warnings = unflattenable_panels(cut, options.skip_unflattenable);
  out.pieces.resize(panels.size());
  std::vector<Points> xyz(panels.size());
  const auto flatten_all = [&](const std::vector<std::vector<HeldEdge>>* held, const FlattenOptions& flatten) {
    parallel_for(0, panels.size(), 1, [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k) {
        const Panel& panel = panels[k];
        PatternPiece& piece = out.pieces[k];
        if (!panel.problem.empty() || (held && (*held)[k].empty())) continue;
        if (!held) {
          xyz[k].resize(static_cast<Eigen::Index>(panel.vertices.size()), 3);
          for (std::size_t v = 0; v < panel.vertices.size(); ++v)
            xyz[k].row(static_cast<Eigen::Index>(v)) = positions.row(panel.vertices[v]);
        }
        const Flattening f = held ? flatten_piece(xyz[k], panel.triangles, flatten, (*held)[k], &piece.uv)
                                  : flatten_piece(xyz[k], panel.triangles, flatten);
        piece.uv = f.uv;
        piece.iterations += f.iterations;
        piece.flatten_ms += f.factor_ms + f.conformal_ms + f.arap_ms;
        piece.converged = f.converged;
        piece.seams_held = held != nullptr;
        piece.flattened = true;
      }
    });
  };
  // Pass 1, plain ARAP. Pass 2 holds the seams' edges where pass 1 left a
  // seam's two sides more than `seam_tolerance` apart: each panel with such a
  // seam is flattened again with every seam of it held, a side at the length of
  // the other side where that panel is not flattened again, else at both sides'
  // mean. Holding trades stretch for agreement, so a panel whose seams already
  // agree (a skirt sewn to itself) keeps its plain flattening, and its time.
  flatten_all(nullptr, options.flatten);
  const auto side_length = [&](const Seam& s, int side) { return indexed_length(out.pieces[s.panel[side]].uv, s.path[side], false); };
  const auto both_flattened = [&](const Seam& s) { return out.pieces[s.panel[0]].flattened && out.pieces[s.panel[1]].flattened; };
  // The seam's two sides more than `fraction` of their mean length apart.
  const auto apart = [&](const Seam& s, double fraction) {
    const double l0 = side_length(s, 0), l1 = side_length(s, 1);
    return std::abs(l0 - l1) > fraction * (0.5 * (l0 + l1));
  };
  std::vector<std::uint8_t> again(panels.size(), 0);
  if (options.flatten.boundary_weight > 0)
    for (const Seam& s : cut.panels.seams)
      if (both_flattened(s) && (options.seam_tolerance <= 0 || apart(s, options.seam_tolerance)))
        again[s.panel[0]] = again[s.panel[1]] = 1;
  std::vector<std::vector<HeldEdge>> held(panels.size());
  for (const Seam& s : cut.panels.seams) {
    if (!both_flattened(s) || !(again[s.panel[0]] || again[s.panel[1]])) continue;
    const double l3 = indexed_length(positions, s.garment_path, false);
    const double l2 = again[s.panel[0]] && again[s.panel[1]] ? 0.5 * (side_length(s, 0) + side_length(s, 1))
                                                              : side_length(s, again[s.panel[0]] ? 1 : 0);
    const double f = l3 > 0 ? l2 / l3 : 1.0;
    for (int side = 0; side < 2; ++side) {
      if (!again[s.panel[side]]) continue;
      for (std::size_t i = 0; i + 1 < s.path[side].size(); ++i)
        held[s.panel[side]].push_back({s.path[side][i], s.path[side][i + 1],
                                       f * (positions.row(s.garment_path[i]) - positions.row(s.garment_path[i + 1])).norm()});
    }
  }
  flatten_all(&held, options.flatten);
  // A seam still more than `seam_agreement` apart (a small tab sewn along most
  // of its outline to a larger piece): its pieces once more, held ten times as hard.
  std::vector<std::vector<HeldEdge>> harder(panels.size());
  for (const Seam& s : cut.panels.seams) {
    if (!both_flattened(s) || !again[s.panel[0]] || !again[s.panel[1]] || !apart(s, options.seam_agreement)) continue;
    for (const Index k : s.panel)
      if (harder[k].empty()) harder[k] = held[k];
  }
  FlattenOptions hard = options.flatten;
  hard.boundary_weight *= 10;
  flatten_all(&harder, hard);
  for (std::size_t k = 0; k < panels.size(); ++k) {
    PatternPiece& piece = out.pieces[k];
    if (!piece.flattened) continue;
    piece.rotation = grain_rotation(xyz[k], piece.uv, panels[k].triangles, options.up);
    piece.uv = rotated(piece.uv, piece.rotation);
    measure(g, cut.panels, k, xyz[k], piece);
  }

  // Seams: the two sides' lengths in 2D (rotation and placement do not change them).
  out.seams.resize(cut.panels.seams.size());
  for (std::size_t i = 0; i < cut.panels.seams.size(); ++i) {
    const Seam& s = cut.panels.seams[i];
    SeamMeasure& m = out.seams[i];
    m.length_3d = indexed_length(positions, s.garment_path, false);
    if (!out.pieces[s.panel[0]].flattened || !out.pieces[s.panel[1]].flattened) continue;
    for (int side = 0; side < 2; ++side) m.length_2d[side] = indexed_length(out.pieces[s.panel[side]].uv, s.path[side], false);
    const double mean = 0.5 * (m.length_2d[0] + m.length_2d[1]);
    m.mismatch = mean > 0 ? std::abs(m.length_2d[0] - m.length_2d[1]) / mean : 0.0;
    out.seam_mismatch_max = std::max(out.seam_mismatch_max, m.mismatch);
  }

  // Layout: pieces packed by their boxes, then moved there.
  std::vector<Box> boxes(panels.size());
  std::vector<Eigen::Vector2d> low(panels.size(), Eigen::Vector2d::Zero());
  std::vector<double> faces_stretch;
  for (std::size_t k = 0; k < panels.size(); ++k) {
    const PatternPiece& piece = out.pieces[k];
    if (!piece.flattened) continue;
    low[k] = piece.uv.colwise().minCoeff().transpose();
    const Eigen::Vector2d high = piece.uv.colwise().maxCoeff().transpose();
    boxes[k] = {high.x() - low[k].x(), high.y() - low[k].y()};
    faces_stretch.insert(faces_stretch.end(), piece.face_stretch.begin(), piece.face_stretch.end());
    if (piece.measures.stretch_p95 > options.stretch_warning)
      out.warnings.push_back("panel '" + panels[k].name + "' stretches by more than " +
                             percent(piece.measures.stretch_p95) + " on 5 % of its faces: it may need a cut (a seam curve)");
    if (piece.measures.flipped > 0)
      out.warnings.push_back("panel '" + panels[k].name + "': " + std::to_string(piece.measures.flipped) +
                             " faces turned over in 2D");
    if (!(piece.measures.area_3d > 0))
      out.warnings.push_back("panel '" + panels[k].name + "' has no area in 3D (its faces' corners are collinear or "
                             "coincident): it is drawn as a line or a point");
  }
  const Packing packing = pack_boxes(boxes, options.margin);
  for (std::size_t k = 0; k < panels.size(); ++k)
    if (out.pieces[k].flattened) out.pieces[k].uv.rowwise() += (packing.corner[k] - low[k]).transpose();
  out.width = packing.width;
  out.height = packing.height;
  out.stretch_p95 = percentile(faces_stretch, 95);
  return out;
}

}  // namespace refit
