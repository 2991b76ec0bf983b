#include <refit/body/body_mesh.hpp>
#include <refit/core/error.hpp>
#include <refit/core/parallel.hpp>

#include <cmath>

namespace refit {

void check_body(const BodyMesh& body) {
  const std::string& file = body.path.empty() ? body.name : body.path;
  if (body.triangles.empty()) throw input_error(file, "body has no triangles");
  const Index n = static_cast<Index>(body.vertices.rows());
  for (Index i = 0; i < n; ++i)
    if (!body.vertices.row(i).allFinite())
      throw input_error(file, "vertex " + std::to_string(i + 1) + " is NaN or infinite");
  for (std::size_t t = 0; t < body.triangles.size(); ++t)
    for (Index c : body.triangles[t])
      if (c >= n)
        throw input_error(file, "triangle " + std::to_string(t + 1) + " uses vertex " + std::to_string(c + 1) +
                                    " but the body has " + std::to_string(n) + " vertices");
}

void check_same_connectivity(const BodyMesh& a, const BodyMesh& b) {
  const std::string& fb = b.path.empty() ? b.name : b.path;
  const std::string& fa = a.path.empty() ? a.name : a.path;
  if (a.vertices.rows() != b.vertices.rows())
    throw input_error(fb, "does not correspond to " + fa + ": " + std::to_string(b.vertices.rows()) +
                              " vertices, expected " + std::to_string(a.vertices.rows()));
  if (a.triangles.size() != b.triangles.size())
    throw input_error(fb, "does not correspond to " + fa + ": " + std::to_string(b.triangles.size()) +
                              " triangles, expected " + std::to_string(a.triangles.size()));
  for (std::size_t t = 0; t < a.triangles.size(); ++t) {
    if (a.triangles[t] != b.triangles[t]) {
      const auto& x = a.triangles[t];
      const auto& y = b.triangles[t];
      throw input_error(fb, "does not correspond to " + fa + ": triangle " + std::to_string(t + 1) + " is (" +
                                std::to_string(y[0] + 1) + " " + std::to_string(y[1] + 1) + " " +
                                std::to_string(y[2] + 1) + "), expected (" + std::to_string(x[0] + 1) + " " +
                                std::to_string(x[1] + 1) + " " + std::to_string(x[2] + 1) + ")");
    }
  }
}

TriangleFrames compute_frames(const BodyMesh& body) {
  const std::size_t n = body.triangles.size();
  TriangleFrames f;
  f.centre.resize(static_cast<Eigen::Index>(n), 3);
  f.u.resize(static_cast<Eigen::Index>(n), 3);
  f.v.resize(static_cast<Eigen::Index>(n), 3);
  f.w.resize(static_cast<Eigen::Index>(n), 3);
  f.valid.assign(n, 0);
  parallel_for(0, n, 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t t = begin; t < end; ++t) {
      const auto& tri = body.triangles[t];
      const Vec3 p0 = row3(body.vertices, tri[0]);
      const Vec3 p1 = row3(body.vertices, tri[1]);
      const Vec3 p2 = row3(body.vertices, tri[2]);
      const Eigen::Index r = static_cast<Eigen::Index>(t);
      f.centre.row(r) = ((p0 + p1 + p2) / 3.0).transpose();
      const Vec3 e1 = p1 - p0;
      const Vec3 n = e1.cross(p2 - p0);
      const double e1n = e1.norm(), nn = n.norm();
      // Zero-area triangles have no frame: mark them so the warp never divides by zero.
      if (!(e1n > 0.0) || !(nn > 1e-12 * e1n * e1n) || !std::isfinite(nn)) {
        f.u.row(r).setZero();
        f.v.row(r).setZero();
        f.w.row(r).setZero();
        continue;
      }
      const Vec3 u = e1 / e1n, w = n / nn;
      f.u.row(r) = u.transpose();
      f.w.row(r) = w.transpose();
      f.v.row(r) = w.cross(u).transpose();
      f.valid[t] = 1;
    }
  });
  for (auto v : f.valid) f.degenerate += v ? 0 : 1;
  return f;
}

}  // namespace refit
