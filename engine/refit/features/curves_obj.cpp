#include <refit/features/curves_obj.hpp>

#include <refit/io/atomic_file.hpp>

#include <cstdio>
#include <ostream>
#include <utility>

namespace refit {
namespace {

// Appends one polyline group; `next` is the OBJ index (1-based) of its first vertex.
void polyline(std::ostream& out, const std::string& group, const Points& p, bool closed, std::size_t& next) {
  out << "g " << group << "\n";
  char buf[96];
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    std::snprintf(buf, sizeof buf, "v %.9g %.9g %.9g\n", p(i, 0), p(i, 1), p(i, 2));
    out << buf;
  }
  out << "l";
  for (Eigen::Index i = 0; i < p.rows(); ++i) out << ' ' << next + static_cast<std::size_t>(i);
  if (closed && p.rows() > 2) out << ' ' << next;
  out << "\n";
  next += static_cast<std::size_t>(p.rows());
}

}  // namespace

void write_curves_obj(const std::string& path, const std::vector<FeatureCurve>& curves) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "# refit feature curves: sampled on the original garment\n";
    std::size_t next = 1;
    for (const FeatureCurve& c : curves) polyline(out, c.name + "_original", c.samples, c.closed, next);
  });
}

void write_curves_obj(const std::string& path, const FeatureResult& result) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "# refit feature curves: original, warped and optimised samples\n";
    std::size_t next = 1;
    for (const CurveResult& c : result.curves) {
      polyline(out, c.name + "_original", c.original, c.closed, next);
      polyline(out, c.name + "_warped", c.warped, c.closed, next);
      polyline(out, c.name + "_optimised", c.optimised, c.closed, next);
    }
  });
}

}  // namespace refit
