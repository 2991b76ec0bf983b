// Feature curves on pattern pieces: samples attached to fan triangles of the
// original garment's faces (attach/), then cut into runs per panel.
#include <refit/patterns/feature_lines.hpp>

#include <refit/attach/attachment.hpp>

#include <algorithm>
#include <optional>

namespace refit {
namespace {

// The face and fan index of an attachment triangle (face[0], face[k], face[k+1]).
class FanLookup {
 public:
  explicit FanLookup(const Garment& g) : g_(g) {
    const std::size_t nf = g.faces.rows();
    by_first_.offsets.assign(g.vertex_count() + 1, 0);
    for (std::size_t f = 0; f < nf; ++f) ++by_first_.offsets[g.faces.row(f)[0] + 1];
    for (std::size_t v = 0; v < g.vertex_count(); ++v) by_first_.offsets[v + 1] += by_first_.offsets[v];
    by_first_.indices.resize(nf);
    std::vector<Index> fill(by_first_.offsets.begin(), by_first_.offsets.end() - 1);
    for (std::size_t f = 0; f < nf; ++f) by_first_.indices[fill[g.faces.row(f)[0]]++] = static_cast<Index>(f);
  }

  std::optional<FaceSample> find(const std::array<Index, 3>& v, const std::array<double, 3>& w) const {
    if (v[0] == v[1] || v[1] == v[2]) return std::nullopt;  // on a line or a point
    for (Index f : by_first_.row(v[0])) {
      const auto face = g_.faces.row(f);
      for (Index k = 1; k + 1 < face.size(); ++k)
        if (face[k] == v[1] && face[k + 1] == v[2]) return FaceSample{f, k, w};
    }
    return std::nullopt;
  }

 private:
  const Garment& g_;
  Csr by_first_;
};

template <class Row, class Pts>
Row sample_point(const FaceSample& s, const Pts& xs, const std::array<Index, 3>& rows) {
  Row p = Row::Zero();
  for (int i = 0; i < 3; ++i) p += s.weight[i] * xs.row(rows[i]).transpose();
  return p;
}

}  // namespace

std::vector<FeatureLine> bind_feature_lines(const Garment& original, const PanelSet& panels,
                                            std::span<const FeatureCurve> curves) {
  std::vector<FeatureLine> out;
  if (curves.empty() || original.faces.rows() == 0) return out;
  const SurfaceAttachment at = attach_points(original, all_samples(curves));
  const FanLookup fans(original);
  Eigen::Index row = 0;
  for (const FeatureCurve& c : curves) {
    std::vector<FeatureLine> runs;
    for (Eigen::Index i = 0; i < c.samples.rows(); ++i, ++row) {
      const auto s = fans.find(at.vertex[static_cast<std::size_t>(row)], at.weight[static_cast<std::size_t>(row)]);
      if (!s) {
        if (!runs.empty() && !runs.back().samples.empty()) runs.emplace_back();  // a gap ends the run
        continue;
      }
      const Index panel = panels.face_panel[s->face];
      if (runs.empty() || (!runs.back().samples.empty() && runs.back().panel != panel)) runs.emplace_back();
      runs.back().panel = panel;
      runs.back().samples.push_back(*s);
    }
    std::erase_if(runs, [](const FeatureLine& l) { return l.samples.empty(); });
    // A closed curve: its last run continues into its first when both are on one panel.
    if (c.closed && runs.size() > 1 && runs.front().panel == runs.back().panel) {
      runs.back().samples.insert(runs.back().samples.end(), runs.front().samples.begin(), runs.front().samples.end());
      runs.front() = std::move(runs.back());
      runs.pop_back();
    }
    const bool whole = c.closed && runs.size() == 1 && runs[0].samples.size() == c.size();
    std::size_t k = 0;
    for (FeatureLine& r : runs) {
      if (r.samples.size() < 2) continue;
      r.curve = c.name;
      r.name = k == 0 ? c.name : c.name + "#" + std::to_string(k + 1);
      r.closed = whole;
      ++k;
      out.push_back(std::move(r));
    }
  }
  return out;
}

Points2 line_points(const FeatureLine& line, const PanelSet& panels, const Garment& g, const Points2& uv) {
  Points2 out(static_cast<Eigen::Index>(line.samples.size()), 2);
  for (std::size_t i = 0; i < line.samples.size(); ++i) {
    const FaceSample& s = line.samples[i];
    const Index c0 = g.faces.offsets[s.face];
    const std::array<Index, 3> rows = {panels.corner_vertex[c0], panels.corner_vertex[c0 + s.k],
                                       panels.corner_vertex[c0 + s.k + 1]};
    out.row(static_cast<Eigen::Index>(i)) = sample_point<Eigen::Vector2d>(s, uv, rows).transpose();
  }
  return out;
}

Points line_points_3d(const FeatureLine& line, const Garment& g, const Points& positions) {
  Points out(static_cast<Eigen::Index>(line.samples.size()), 3);
  for (std::size_t i = 0; i < line.samples.size(); ++i) {
    const FaceSample& s = line.samples[i];
    const auto face = g.faces.row(s.face);
    const std::array<Index, 3> rows = {face[0], face[s.k], face[s.k + 1]};
    out.row(static_cast<Eigen::Index>(i)) = sample_point<Vec3>(s, positions, rows).transpose();
  }
  return out;
}

}  // namespace refit
