// The pattern report; see report.hpp.
#include <refit/patterns/report.hpp>

#include <refit/patterns/darts.hpp>
#include <refit/patterns/lengths.hpp>

namespace refit {
namespace {

double change(double now, double before) { return before > 0 ? now / before - 1 : 0.0; }

}  // namespace

nlohmann::json pattern_report(const Garment& g, const PatternCut& cut, const Pattern& pattern, const Points& positions,
                              const std::string& units) {
  using json = nlohmann::json;
  json panels = json::array();
  for (std::size_t k = 0; k < cut.panels.panels.size(); ++k) {
    const Panel& p = cut.panels.panels[k];
    const PatternPiece& piece = pattern.pieces[k];
    json j = {{"name", p.name},
              {"faces", p.faces.size()},
              {"vertices", p.vertices.size()},
              {"boundary_loops", p.loops.size()},
              {"flattened", piece.flattened}};
    if (!p.problem.empty()) j["problem"] = p.problem;
    if (piece.flattened) {
      const PieceMeasures& m = piece.measures;
      j["area_3d"] = m.area_3d;
      j["area_2d"] = m.area_2d;
      j["area_change"] = change(m.area_2d, m.area_3d);
      j["perimeter_3d"] = m.perimeter_3d;
      j["perimeter_2d"] = m.perimeter_2d;
      j["perimeter_change"] = change(m.perimeter_2d, m.perimeter_3d);
      j["stretch"] = {{"p50", m.stretch_p50}, {"p95", m.stretch_p95}, {"max", m.stretch_max},
                      {"triangle_p95", m.triangle_stretch_p95}};
      j["flipped_faces"] = m.flipped;
      j["iterations"] = piece.iterations;
      j["converged"] = piece.converged;
      j["seams_held"] = piece.seams_held;
      j["flatten_ms"] = piece.flatten_ms;
      json outlines = json::array();
      for (const auto& loop : p.loops) {
        outlines.push_back(indexed_length(piece.uv, loop, true));
      }
      j["outline_lengths"] = outlines;
      json lines = json::array();
      for (const FeatureLine& line : cut.lines)
        if (line.panel == k)
          lines.push_back({{"name", line.name},
                           {"samples", line.samples.size()},
                           {"length_3d", rows_length(line_points_3d(line, g, positions), line.closed)},
                           {"length_2d", rows_length(line_points(line, cut.panels, g, piece.uv), line.closed)}});
      j["feature_lines"] = lines;
    }
    json darts = json::array();
    for (const Dart& d : cut.darts) {
      if (d.panel != k) continue;
      json dj = {{"vertices", d.garment_path.size()}, {"length_3d", indexed_length(positions, d.garment_path, false)}};
      const long s = dart_seam(cut, d);
      if (s >= 0 && piece.flattened) {
        const SeamMeasure& m = pattern.seams[static_cast<std::size_t>(s)];
        dj["length_2d"] = {m.length_2d[0], m.length_2d[1]};
        dj["mismatch"] = m.mismatch;
      }
      darts.push_back(dj);
    }
    j["darts"] = darts;
    panels.push_back(j);
  }
  json seams = json::array();
  for (std::size_t i = 0; i < cut.panels.seams.size(); ++i) {
    const Seam& s = cut.panels.seams[i];
    const SeamMeasure& m = pattern.seams[i];
    seams.push_back({{"panels", {cut.panels.panels[s.panel[0]].name, cut.panels.panels[s.panel[1]].name}},
                     {"edges", s.garment_path.size() - 1},
                     {"length_3d", m.length_3d},
                     {"length_2d", {m.length_2d[0], m.length_2d[1]}},
                     {"mismatch", m.mismatch}});
  }
  json curves = json::array();
  for (const SeamPath& sp : cut.seam_paths)
    curves.push_back({{"name", sp.name}, {"vertices", sp.vertices.size()}, {"deviation", sp.deviation}});
  const PanelSet& ps = cut.panels;
  return {{"units", units},
          {"sheet", {{"width", pattern.width}, {"height", pattern.height}}},
          {"panels_total", ps.panels.size()},
          {"stretch_p95", pattern.stretch_p95},
          {"seam_mismatch_max", pattern.seam_mismatch_max},
          {"darts", cut.darts.size()},
          {"cuts", {{"uv_seam_edges", ps.uv_seam_edges}, {"group_edges", ps.group_edges},
                    {"seam_curve_edges", ps.curve_edges}, {"non_manifold_edges", ps.non_manifold_edges}}},
          {"seam_curves", curves},
          {"panels", panels},
          {"seams", seams},
          {"warnings", pattern.warnings}};
}

std::vector<std::string> panel_lines(const PatternCut& cut) {
  std::vector<std::string> out;
  for (const Panel& p : cut.panels.panels) {
    std::string line = p.name + ": " + std::to_string(p.faces.size()) + " faces, " + std::to_string(p.vertices.size()) +
                       " vertices, " + std::to_string(p.loops.size()) + " boundary loops";
    if (!p.problem.empty()) line += "; cannot be flattened: " + p.problem;
    out.push_back(line);
  }
  return out;
}

}  // namespace refit
