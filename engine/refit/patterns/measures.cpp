// Measures of a flattened piece; see measures.hpp.
#include <refit/patterns/measures.hpp>

#include <refit/core/parallel.hpp>
#include <refit/patterns/lengths.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace refit {

std::array<double, 2> face_singular_values(const Points& xyz, const Points2& uv) {
  const Eigen::RowVector3d c = xyz.colwise().mean();
  const Points d = xyz.rowwise() - c;
  // The face's plane: the two main directions of its corners, oriented by the corners' winding (Newell normal).
  Vec3 normal = Vec3::Zero();
  for (Eigen::Index i = 0; i < xyz.rows(); ++i) normal += row3(xyz, static_cast<Index>(i)).cross(row3(xyz, static_cast<Index>((i + 1) % xyz.rows())));
  if (!(normal.norm() > 0)) return {0.0, 0.0};
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pca(d.transpose() * d);
  Vec3 e1 = pca.eigenvectors().col(2);
  Vec3 e2 = normal.normalized().cross(e1);
  e1 = e2.cross(normal.normalized());
  Eigen::Matrix<double, Eigen::Dynamic, 2> x(xyz.rows(), 2);
  x.col(0) = d * e1;
  x.col(1) = d * e2;
  const Points2 q = uv.rowwise() - uv.colwise().mean();
  const Eigen::Matrix2d xx = x.transpose() * x;
  if (!(std::abs(xx.determinant()) > 1e-30 * xx.squaredNorm())) return {0.0, 0.0};
  const Eigen::Matrix2d J = (q.transpose() * x) * xx.inverse();
  // Closed-form 2x2 singular values; the second negative when J turns over.
  const double E = 0.5 * (J(0, 0) + J(1, 1)), F = 0.5 * (J(0, 0) - J(1, 1));
  const double G = 0.5 * (J(1, 0) + J(0, 1)), H = 0.5 * (J(1, 0) - J(0, 1));
  const double a = std::hypot(E, H), b = std::hypot(F, G);
  return {a + b, a - b};
}

double log_stretch(const std::array<double, 2>& s) {
  if (s[0] == 0 && s[1] == 0) return 0.0;  // no area in 3D: nothing to stretch
  // A face turned over is counted apart (PieceStretch::flipped); a collapsed one stays finite.
  const auto log_of = [](double x) { return std::abs(std::log(std::max(std::abs(x), 1e-12))); };
  return std::max(log_of(s[0]), log_of(s[1]));
}

PieceStretch measure_piece(const Garment& g, const PanelSet& set, std::size_t k, const Points& xyz, const Points2& uv) {
  const Panel& panel = set.panels[k];
  const std::size_t nf = panel.faces.size(), nt = panel.triangles.size();
  // Each face's first triangle (the triangles come in face order): the faces are then measured in parallel.
  std::vector<std::size_t> first(nf + 1, 0);
  for (std::size_t i = 0, t = 0; i < nf; ++i) {
    first[i] = t;
    while (t < nt && panel.triangle_face[t] == panel.faces[i]) ++t;
    first[i + 1] = t;
  }
  PieceStretch out;
  out.face.resize(nf);
  out.triangle.resize(first[nf]);
  std::vector<std::uint8_t> flipped(nf, 0);
  std::vector<double> area_3d(first[nf], 0.0), area_2d(first[nf], 0.0);
  parallel_for(0, nf, 1024, [&](std::size_t b, std::size_t e) {
    Points p3;
    Points2 p2;
    std::vector<Index> corners;
    const auto gather = [&](auto rows) {
      p3.resize(static_cast<Eigen::Index>(rows.size()), 3);
      p2.resize(static_cast<Eigen::Index>(rows.size()), 2);
      for (std::size_t i = 0; i < rows.size(); ++i) {
        p3.row(static_cast<Eigen::Index>(i)) = xyz.row(rows[i]);
        p2.row(static_cast<Eigen::Index>(i)) = uv.row(rows[i]);
      }
    };
    for (std::size_t i = b; i < e; ++i) {
      const Index f = panel.faces[i];
      const Index c0 = g.faces.offsets[f];
      corners.assign(set.corner_vertex.begin() + c0, set.corner_vertex.begin() + c0 + g.faces.row_size(f));
      // In the panel's winding: a face the panel turned (panels.cpp) has its fan reversed.
      const std::size_t t0 = first[i];
      if (t0 < nt && corners.size() >= 3 && panel.triangles[t0][1] != corners[1])
        std::reverse(corners.begin() + 1, corners.end());
      gather(std::span<const Index>(corners));
      const std::array<double, 2> sv = face_singular_values(p3, p2);
      out.face[i] = log_stretch(sv);
      flipped[i] = sv[1] < 0;
      for (std::size_t t = t0; t < first[i + 1]; ++t) {
        const Triangle& tri = panel.triangles[t];
        gather(std::span<const Index>(tri));
        out.triangle[t] = log_stretch(face_singular_values(p3, p2));
        const Vec3 a = row3(xyz, tri[0]), bb = row3(xyz, tri[1]), c = row3(xyz, tri[2]);
        area_3d[t] = 0.5 * (bb - a).cross(c - a).norm();
        const Eigen::Vector2d u = uv.row(tri[1]) - uv.row(tri[0]), h = uv.row(tri[2]) - uv.row(tri[0]);
        area_2d[t] = 0.5 * (u.x() * h.y() - u.y() * h.x());
      }
    }
  });
  // Summed in triangle order whatever the threads.
  for (std::size_t t = 0; t < first[nf]; ++t) out.area_3d += area_3d[t], out.area_2d += area_2d[t];
  for (std::uint8_t x : flipped) out.flipped += x;
  for (const auto& loop : panel.loops) {
    out.perimeter_3d += indexed_length(xyz, loop, true);
    out.perimeter_2d += indexed_length(uv, loop, true);
  }
  return out;
}

}  // namespace refit
