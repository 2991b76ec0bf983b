// End to end on the procedural dress: warp (step 1), feature curves (step 2),
// then the surface (step 3) to a body with a belly bump.
#include <refit/body/body_surface.hpp>
#include <refit/core/parallel.hpp>
#include <refit/features/curve_metrics.hpp>
#include <refit/features/feature_curves.hpp>
#include <refit/features/feature_file.hpp>
#include <refit/features/shape_matching.hpp>

#include <Eigen/Geometry>
#include <Eigen/SparseLU>
#include <refit/surface/surface.hpp>
#include <refit/warp/warp.hpp>

#include <mannequin/mannequin.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <limits>
#include <map>
#include <numbers>

namespace refit {
namespace {

namespace mq = refit::mannequin;

struct Case {
  Garment dress;
  Points warped, result;
  SurfaceStats stats;
  std::vector<CurveResult> curves;
  double skirt_top = 0, skirt_bottom = 0;
  std::vector<double> body_distance;  // of each warped vertex to body B
  std::size_t inside = 0;             // result vertices inside body B
};

// `inspect`, when given, sees the binding and the fine system of its last solve.
using Inspect = std::function<void(const SurfaceBinding&, const SurfaceSystem&)>;

Case run_dress(bool soup, std::size_t target_vertices = 6000, SurfaceOptions so = {}, bool same_body = false,
               bool two_layers = false, const Inspect& inspect = {}) {
  const mq::BodyParams a{};
  mq::BodyParams b = a;
  if (!same_body) {
    b.belly = 8;
    b.hip = a.hip + 6;
  }
  mq::GarmentParams gp;
  gp.kind = mq::GarmentParams::Kind::Dress;
  gp.target_vertices = target_vertices;
  gp.soup = soup;
  gp.two_layers = two_layers;
  gp.ease = -0.5;  // bodice 1 cm over the body: on the edge of epsilon
  Case c;
  c.dress = mq::make_garment(a, gp);
  const ReferenceBody ref(mq::make_body(a));
  const BodyMesh body_b = mq::make_body(b);
  const TriangleFrames frames_b = compute_frames(body_b);
  const BodySurface surface_b(body_b);
  c.warped = ref.bind(c.dress.positions).apply(frames_b);

  const auto specs = parse_feature_json(mq::dress_features_json(a, gp), "dress_features.json", "cm");
  // Feature samples from the features module (slices of the original dress);
  // warped with step 1; targets made here, independent of step 2: the original
  // profile moved onto the warped one by the best similarity (Umeyama), that is
  // a profile with exactly its original shape where the warp put it.
  const auto curves = build_feature_curves(c.dress, specs);
  const WarpBinding fw_bind = [&] {
    std::size_t m = 0;
    for (const auto& fc : curves) m += fc.samples.rows();
    Points all(Eigen::Index(m), 3);
    Eigen::Index r = 0;
    for (const auto& fc : curves) {
      all.middleRows(r, fc.samples.rows()) = fc.samples;
      r += fc.samples.rows();
    }
    return ref.bind(all);
  }();
  const Points all_warped = fw_bind.apply(frames_b);
  std::size_t m = 0;
  for (const auto& fc : curves) m += fc.samples.rows();
  Points samples(Eigen::Index(m), 3), targets(Eigen::Index(m), 3), fwarped = all_warped;
  Eigen::Index row = 0;
  for (const auto& fc : curves) {
    const Eigen::Index k = fc.samples.rows();
    samples.middleRows(row, k) = fc.samples;
    const Eigen::Matrix3Xd src = fc.samples.transpose(), dst = all_warped.middleRows(row, k).transpose();
    const Eigen::Matrix4d t = Eigen::umeyama(src, dst, true);
    targets.middleRows(row, k) = ((t.topLeftCorner<3, 3>() * src).colwise() + t.topRightCorner<3, 1>()).transpose();
    CurveResult cr;
    cr.name = fc.name;
    cr.original = fc.samples;
    cr.warped = all_warped.middleRows(row, k);
    cr.optimised = targets.middleRows(row, k);
    c.curves.push_back(cr);
    row += k;
  }
  const SurfaceBinding sb = SurfaceBinding::bind(c.dress, samples, so);
  SurfaceSystem system;
  const SurfaceResult r = sb.apply(c.warped, targets, surface_b, &fwarped, inspect ? &system : nullptr);
  if (inspect) inspect(sb, system);
  c.result = r.positions;
  c.stats = r.stats;
  const mq::Landmarks lv = mq::landmarks(a);
  c.skirt_top = lv.waist;
  c.skirt_bottom = lv.knee;
  c.body_distance.resize(c.warped.rows());
  for (Eigen::Index v = 0; v < c.warped.rows(); ++v) c.body_distance[v] = surface_b.closest(row3(c.warped, Index(v))).distance;
  for (Eigen::Index v = 0; v < c.result.rows(); ++v) c.inside += surface_b.inside(row3(c.result, Index(v)));
  return c;
}

// Garment vertices within `band` of a vertical half plane through the body axis at
// angle phi (0 = +x, pi/2 = front), on the skirt, ordered by height: a "curve" whose
// shape in the original, the warp and the result can be compared. Vertices from
// `first` on (the outer layer of a two-layer dress).
std::vector<Index> half_plane_vertices(const Case& c, double phi, double band, Eigen::Index first = 0) {
  const Vec3 dir(std::cos(phi), 0, std::sin(phi)), normal(-std::sin(phi), 0, std::cos(phi));
  std::vector<std::pair<double, Index>> found;
  for (Eigen::Index v = first; v < c.dress.positions.rows(); ++v) {
    const Vec3 p = row3(c.dress.positions, Index(v));
    if (p.y() > c.skirt_top - 3 || p.y() < c.skirt_bottom + 3) continue;
    if (std::abs(p.dot(normal)) < band && p.dot(dir) > 0) found.emplace_back(p.y(), Index(v));
  }
  std::sort(found.begin(), found.end());
  std::vector<Index> out;
  for (const auto& f : found) out.push_back(f.second);
  return out;
}
Points rows_of(const Points& p, const std::vector<Index>& idx) {
  Points out(Eigen::Index(idx.size()), 3);
  for (std::size_t i = 0; i < idx.size(); ++i) out.row(Eigen::Index(i)) = p.row(idx[i]);
  return out;
}

TEST(SurfaceDress, FollowsTheProfilesAndKeepsTheBodyContact) {
  // The paper's rule (no feature zone): eq. 14 everywhere but on the feature
  // agents. The default zone is tested below.
  SurfaceOptions paper_rule;
  paper_rule.feature_zone_rings = 0;
  paper_rule.near_body_band = 0.0;  // eq. 14 on the hanging dress too (the band is tested below)
  const Case c = run_dress(false, 6000, paper_rule);
  ASSERT_TRUE(c.result.allFinite());
  EXPECT_GT(c.stats.fixed_feature, 0u);
  EXPECT_GT(c.stats.fixed_body, 0u);
  std::printf("dress: %zu vertices, %zu agents (voxel %.3f cm), degree %.2f/%zu, fixed body %zu feature %zu, "
              "anchored %zu in %zu groups, %d levels, %d iterations (+%d coarse), update %.2e, ms: sample %.1f agents %.1f one_ring %.1f "
              "encode %.1f solve %.1f reconstruct %.1f\n",
              c.dress.vertex_count(), c.stats.agents, c.stats.voxel, c.stats.ring_degree_mean, c.stats.ring_degree_max,
              c.stats.fixed_body, c.stats.fixed_feature, c.stats.anchored, c.stats.anchored_groups, c.stats.levels,
              c.stats.iterations, c.stats.coarse_iterations,
              c.stats.final_update, c.stats.ms.sample, c.stats.ms.agents, c.stats.ms.one_ring, c.stats.ms.encode,
              c.stats.ms.solve, c.stats.ms.reconstruct);

  // Vertices within 1 cm of body B stay (nearly) where the warp put them.
  double worst_near = 0.0;
  std::size_t near = 0;
  for (Eigen::Index v = 0; v < c.warped.rows(); ++v)
    if (c.body_distance[v] < 1.0) {
      ++near;
      worst_near = std::max(worst_near, (c.result.row(v) - c.warped.row(v)).norm());
    }
  std::printf("  %zu vertices within 1 cm of body B: largest move %.4f cm\n", near, worst_near);
  EXPECT_GT(near, 100u);
  EXPECT_LT(worst_near, 1e-12);

  // The side profiles (features at phi = 0 and pi) and a held-out slice between
  // the side and the front profiles (phi = pi/4, not a feature).
  for (const double phi : {0.0, std::numbers::pi, std::numbers::pi / 4, 3 * std::numbers::pi / 4}) {
    const auto idx = half_plane_vertices(c, phi, 0.4);
    ASSERT_GE(idx.size(), 10u) << phi;
    const Points orig = rows_of(c.dress.positions, idx);
    const double e_warp = shape_error(rows_of(c.warped, idx), orig, false);
    const double e_res = shape_error(rows_of(c.result, idx), orig, false);
    std::printf("  slice at %.0f deg (%zu vertices): shape error warp %.5f result %.5f (gain %.1f)\n",
                phi * 180 / std::numbers::pi, idx.size(), e_warp, e_res, e_warp / e_res);
    const bool feature = std::abs(std::sin(phi)) < 1e-9;
    // The targets: 10x on the profiles, 3x on a held-out slice between
    // them. Measured (vertices within 0.4 cm of the plane): 62x and 107x on the
    // profiles, 4.2x and 3.2x between them (4.5x and 3.6x before agents were
    // held clear of the body, by sinking into its hips; the paper's frames and
    // blend: 8x, 7x, 3.3x, 2.7x).
    EXPECT_LT(e_res * (feature ? 10.0 : 3.0), e_warp) << "slice at " << phi;
  }
  // The feature curves themselves (step 2's own numbers, for the record).
  for (const auto& cr : c.curves)
    std::printf("  curve %s: shape error warp %.5f target %.5f\n", cr.name.c_str(),
                shape_error(cr.warped, cr.original, false), shape_error(cr.optimised, cr.original, false));
}

TEST(SurfaceDress, TheFeatureZoneLetsTheFeaturesWinNearThemAndSnapsTheGarmentThroughThem) {
  // The default feature zone (one one-ring step): near a feature agent eq. 14
  // gives way, and the written garment is snapped through the optimised curves.
  // Eq. 14 away from the features (the band, which frees it on a hanging piece, is tested below).
  SurfaceOptions zoned;
  ASSERT_EQ(zoned.feature_zone_rings, 1);
  zoned.near_body_band = 0.0;
  zoned.feature_slide_rings = 0;  // the zone alone (the slide beside it: BesideAFeatureTheKeptSurfaceBeginsRingsAway)
  SurfaceOptions paper_rule = zoned;
  paper_rule.feature_zone_rings = 0;
  const Case plain = run_dress(false, 6000, paper_rule);
  const Case c = run_dress(false, 6000, zoned);
  ASSERT_TRUE(c.result.allFinite());
  EXPECT_GT(c.stats.feature_zone_agents, c.stats.fixed_feature);
  EXPECT_LT(c.stats.fixed_body, plain.stats.fixed_body);
  EXPECT_EQ(plain.stats.vertices_snapped, 0u);  // no zone, no snap
  EXPECT_GT(c.stats.vertices_snapped, 0u);
  std::printf("  zone: %zu agents, fixed body %zu (without a zone %zu); feature gap %.4f -> %.4f cm, %zu vertices "
              "snapped\n",
              c.stats.feature_zone_agents, c.stats.fixed_body, plain.stats.fixed_body, c.stats.feature_gap_before_snap,
              c.stats.feature_gap, c.stats.vertices_snapped);
  // The largest gap left is where two curves meet: this test's targets are each
  // curve's own similarity fit, so they disagree there (step 2 makes crossings agree).
  EXPECT_LT(c.stats.feature_gap, c.stats.feature_gap_before_snap);
  // Near the body and away from every feature (farther than the zone's one-ring
  // radius and a vertex's reach), vertices still stay exactly as warped.
  const double away = (zoned.ring_radius_voxels + zoned.reach_voxels + 1.0) * c.stats.voxel;
  std::size_t far_near = 0, zone_near_moved = 0;
  double worst_far = 0.0;
  for (Eigen::Index v = 0; v < c.warped.rows(); ++v) {
    if (c.body_distance[v] >= 1.0) continue;
    const Vec3 p = row3(c.dress.positions, Index(v));
    double nearest = std::numeric_limits<double>::infinity();
    for (const auto& cr : c.curves)
      for (Eigen::Index k = 0; k < cr.original.rows(); ++k) nearest = std::min(nearest, (row3(cr.original, Index(k)) - p).norm());
    const double move = (c.result.row(v) - c.warped.row(v)).norm();
    if (nearest > away) {
      ++far_near;
      worst_far = std::max(worst_far, move);
    } else {
      zone_near_moved += move > 1e-9;
    }
  }
  std::printf("  %zu vertices within 1 cm of body B and %.1f cm from the features: largest move %.2e cm; %zu nearer ones moved\n",
              far_near, away, worst_far, zone_near_moved);
  EXPECT_GT(far_near, 100u);
  EXPECT_LT(worst_far, 1e-12);
  EXPECT_GT(zone_near_moved, 0u);
  // The profiles: at least the gain without a zone (measured 62x and 107x without,
  // about 1000x with).
  for (const double phi : {0.0, std::numbers::pi}) {
    const auto idx = half_plane_vertices(c, phi, 0.4);
    const Points orig = rows_of(c.dress.positions, idx);
    const double e_plain = shape_error(rows_of(plain.result, idx), orig, false);
    const double e_zone = shape_error(rows_of(c.result, idx), orig, false);
    const double e_warp = shape_error(rows_of(c.warped, idx), orig, false);
    std::printf("  profile at %.0f deg: gain over the warp %.1f without a zone, %.1f with\n", phi * 180 / std::numbers::pi,
                e_warp / e_plain, e_warp / e_zone);
    EXPECT_LT(e_zone, e_plain);
  }
}

// Where the feature zone meets the vertices eq. 14 keeps at the warp, the zone's
// reconstruction stands off the warp. All or nothing, that difference is a step
// between two neighbouring vertices, a cliff on a fine mesh; eased by the blend's
// share outside the zone, a slope over about a voxel whatever the mesh.
// Per edge from a vertex kept exactly at the warp to a neighbour near body B
// that is not: how far the neighbour stands off the warp per cm of the edge.
struct KeptEdges {
  double steepest = 0.0;
  std::size_t count = 0, steep = 0;  // edges, and those steeper than 0.1
};
KeptEdges kept_edges(const Case& c) {
  KeptEdges e;
  for (std::size_t f = 0; f < c.dress.faces.rows(); ++f) {
    const auto face = c.dress.faces.row(f);
    for (std::size_t k = 0; k < face.size(); ++k) {
      const Index u = face[k], v = face[(k + 1) % face.size()];
      if (!(c.body_distance[u] < 1.0 && c.body_distance[v] < 1.0)) continue;
      const double mu = (c.result.row(u) - c.warped.row(u)).norm(), mv = (c.result.row(v) - c.warped.row(v)).norm();
      if ((mu == 0.0) == (mv == 0.0)) continue;
      const double slope = std::max(mu, mv) / (c.dress.positions.row(u) - c.dress.positions.row(v)).norm();
      ++e.count;
      e.steep += slope > 0.1;
      e.steepest = std::max(e.steepest, slope);
    }
  }
  return e;
}

TEST(SurfaceDress, TheZoneEdgeIsASlopeNotACliffOnAFineMesh) {
  SurfaceOptions eased;
  ASSERT_GT(eased.zone_edge_blend, 0.0);
  eased.near_body_band = 0.0;
  eased.feature_slide_rings = 0;  // the kept vertices right at the zone (the slide moves them rings away: next test)
  SurfaceOptions cliff = eased;
  cliff.zone_edge_blend = 0.0;
  const Case a = run_dress(false, 60000, cliff), b = run_dress(false, 60000, eased);
  const KeptEdges ea = kept_edges(a), eb = kept_edges(b);
  std::printf("  edges from a vertex kept at the warp to one near body B that is not: all or nothing %zu, steepest %.3f "
              "(%zu over 0.1); eased %zu, steepest %.3f (%zu over 0.1); voxel %.2f cm, %zu and %zu vertices kept\n",
              ea.count, ea.steepest, ea.steep, eb.count, eb.steepest, eb.steep, b.stats.voxel, a.stats.vertices_kept,
              b.stats.vertices_kept);
  ASSERT_GT(ea.count, 0u);
  ASSERT_GT(eb.count, 0u);
  EXPECT_LT(eb.steepest, 0.25 * ea.steepest);
  EXPECT_LT(eb.steep, ea.steep / 4 + 1);
}

TEST(SurfaceDress, BesideAFeatureTheKeptSurfaceBeginsRingsAway) {
  // With the eased zone edge alone, the vertices eq. 14 keeps at the warp begin
  // right beside the zone, which stands off the warp: a slope over a fraction
  // of a voxel. With feature_slide_rings the agents eq. 14 holds near a feature
  // keep a share of the solution that fades over those rings, so the kept
  // vertices begin where the solution has come back to the warp.
  SurfaceOptions slide;
  ASSERT_GT(slide.feature_slide_rings, 0);
  slide.near_body_band = 0.0;
  SurfaceOptions held = slide;
  held.feature_slide_rings = 0;
  const Case a = run_dress(false, 60000, held), b = run_dress(false, 60000, slide);
  EXPECT_EQ(a.stats.feature_slid, 0u);
  EXPECT_GT(b.stats.feature_slid, 0u);
  const KeptEdges ea = kept_edges(a), eb = kept_edges(b);
  std::printf("  edges from a vertex kept at the warp to one near body B that is not: held %zu, steepest %.3f "
              "(%zu over 0.1); slide %zu, steepest %.3f (%zu over 0.1); %zu agents slid, voxel %.2f cm\n",
              ea.count, ea.steepest, ea.steep, eb.count, eb.steepest, eb.steep, b.stats.feature_slid, b.stats.voxel);
  ASSERT_GT(ea.count, 0u);
  ASSERT_GT(eb.count, 0u);
  EXPECT_LT(eb.steepest, 0.5 * ea.steepest);
  EXPECT_LE(eb.steep, ea.steep);
  std::printf("  inside body B: held %zu, slide %zu\n", a.inside, b.inside);
}

TEST(SurfaceDress, TheOuterOfTwoLayersKeepsItsShapeOverTheSlip) {
  // The dress over a slip 1 cm inside it (closer than an agent voxel): with
  // layers each gets its own agents, rings and blends; the paper's one agent
  // per voxel lets the slip's agents (held near the body, no features) into
  // the dress's blends and rings. Measured between the profiles: 4.3x and 3.8x
  // with layers, 3.2x and 3.4x without.
  // The layers' effect is measured with eq. 14 as before (band 0); the default
  // (band on: the hanging dress's agents near the body are solved too) is then
  // closer still between the profiles: 3.9x and 6.7x against 3.1x and 3.6x.
  SurfaceOptions eq14;
  eq14.near_body_band = 0.0;
  eq14.feature_slide_rings = 0;
  SurfaceOptions paper = eq14;
  paper.layers = false;
  const Case c = run_dress(false, 12000, {}, false, true);
  const Case c0 = run_dress(false, 12000, eq14, false, true);
  const Case p = run_dress(false, 12000, paper, false, true);
  EXPECT_EQ(c.stats.layers, 2u);
  EXPECT_TRUE(c.stats.converged);
  const Eigen::Index outer = c.dress.positions.rows() / 2;  // the slip is listed first, as many vertices
  for (const double phi : {0.0, std::numbers::pi, std::numbers::pi / 4, 3 * std::numbers::pi / 4}) {
    const auto idx = half_plane_vertices(c, phi, 0.4, outer);
    ASSERT_GE(idx.size(), 10u) << phi;
    const Points orig = rows_of(c.dress.positions, idx);
    const double e_warp = shape_error(rows_of(c.warped, idx), orig, false);
    const double e_res = shape_error(rows_of(c.result, idx), orig, false);
    const double e_eq14 = shape_error(rows_of(c0.result, idx), orig, false);
    const double e_paper = shape_error(rows_of(p.result, idx), orig, false);
    std::printf("  outer slice at %.0f deg: shape error warp %.5f, default %.5f (gain %.1f); with eq. 14: layers %.5f "
                "(gain %.1f), one agent per voxel %.5f (gain %.1f)\n",
                phi * 180 / std::numbers::pi, e_warp, e_res, e_warp / e_res, e_eq14, e_warp / e_eq14, e_paper,
                e_warp / e_paper);
    const bool feature = std::abs(std::sin(phi)) < 1e-9;
    EXPECT_LT(e_res * (feature ? 10.0 : 3.0), e_warp) << "slice at " << phi;
    if (!feature) {
      EXPECT_LT(e_eq14, e_paper) << "slice at " << phi;
      EXPECT_LT(e_res, e_eq14) << "slice at " << phi;
    }
  }
}

TEST(SurfaceDress, ManifoldAndSoupAgree) {
  // With eq. 14 (band 0) and with the default band, which frees the hanging
  // dress's agents near the body and holds those the solve moves more than the
  // band away: a per-agent threshold, so the two samplings hold different agents
  // (about 525 and 635) and agree less (measured: 25 % of the mean step-3 move
  // with eq. 14, 31 % with the band; the largest difference 1.33 and 1.15 cm).
  for (const double band : {0.0, SurfaceOptions{}.near_body_band}) {
    SurfaceOptions so;
    so.voxel = 1.6;  // the same grid for both (the auto size follows the vertex count)
    so.near_body_band = band;
    const Case m = run_dress(false, 6000, so);
    const Case s = run_dress(true, 6000, so);
    ASSERT_TRUE(s.result.allFinite());
    // Soup vertices that coincide with a manifold vertex in the original.
    std::map<std::array<double, 3>, Index> where;
    for (Eigen::Index v = 0; v < m.dress.positions.rows(); ++v)
      where[{m.dress.positions(v, 0), m.dress.positions(v, 1), m.dress.positions(v, 2)}] = Index(v);
    std::size_t matched = 0;
    double worst = 0.0, sum = 0.0, moved = 0.0;
    for (Eigen::Index v = 0; v < s.dress.positions.rows(); ++v) {
      auto it = where.find({s.dress.positions(v, 0), s.dress.positions(v, 1), s.dress.positions(v, 2)});
      if (it == where.end()) continue;
      ++matched;
      const double d = (s.result.row(v) - m.result.row(it->second)).norm();
      worst = std::max(worst, d);
      sum += d;
      moved += (m.result.row(it->second) - m.warped.row(it->second)).norm();
    }
    std::printf("band %.1f: soup vs manifold: %zu matched vertices, mean difference %.4f cm, max %.4f cm; mean step-3 "
                "move %.4f cm; banded agents %zu / %zu, held at the band %zu / %zu\n",
                band, matched, sum / double(matched), worst, moved / double(matched), m.stats.banded, s.stats.banded,
                m.stats.fixed_band, s.stats.fixed_band);
    EXPECT_GT(matched, m.dress.vertex_count() * 9 / 10);
    // The agents also differ near the soup's extras (flap, drawstrings, buttons)
    // and where the duplicated seams change the samples.
    EXPECT_LT(sum, (band > 0.0 ? 0.35 : 0.3) * moved) << "band " << band;
    EXPECT_LT(worst, 1.5) << "band " << band;
    if (band > 0.0) {
      EXPECT_GT(m.stats.banded, 0u);
    }
  }
}

// The profile shape error (vertices within 0.4 cm of the plane at phi) of a result.
double profile_error(const Case& c, const Points& result, double phi) {
  const auto idx = half_plane_vertices(c, phi, 0.4);
  return shape_error(rows_of(result, idx), rows_of(c.dress.positions, idx), false);
}

TEST(SurfaceDress, DocumentedImprovementsBeatThePapersFramesAndBlend) {
  // The paper's way: fan frames, eq. 4 blend, vertices re-emitted from their
  // warped offsets. Ours: least-squares ring rotations, smooth kernel, original
  // offsets, smoothed displacements (surface.hpp). Measured: profile errors 8x
  // and 7x below the warp the paper's way, 62x and 110x ours.
  SurfaceOptions paper;
  paper.fit_rotations = false;
  paper.smooth_blend = false;
  paper.emit_from_original = false;
  paper.smooth_passes = 0;
  paper.keep_clear_of_body = false;
  const Case p = run_dress(false, 6000, paper);
  const Case o = run_dress(false, 6000);
  ASSERT_TRUE(p.result.allFinite());
  for (const double phi : {0.0, std::numbers::pi}) {
    const double e_paper = profile_error(p, p.result, phi), e_ours = profile_error(o, o.result, phi);
    std::printf("  profile at %.0f deg: shape error paper's way %.5f, ours %.5f\n", phi * 180 / std::numbers::pi, e_paper,
                e_ours);
    EXPECT_LT(e_ours, 0.5 * e_paper) << phi;
  }
}

TEST(SurfaceDress, AgentsTheSolveSinksIntoTheBodyAreHeldClearOfIt) {
  // The bodice (1 cm of ease) and the skirt's top over body B's belly and hips:
  // restored to their original shape they sink into B. The paper's eq. 14 alone
  // (keep_clear_of_body off) leaves that to the collision step.
  // (--paper-surface: no bend around the features either; it has no clearance
  // rounds of its own without keep_clear_of_body, see feature_bend.hpp.)
  SurfaceOptions paper;
  paper.keep_clear_of_body = false;
  paper.feature_bend_radius = 0.0;
  const Case p = run_dress(false, 6000, paper);
  const Case o = run_dress(false, 6000);
  std::printf("  vertices inside body B: eq. 14 alone %zu, held clear %zu (%zu agents held, %d rounds)\n", p.inside,
              o.inside, o.stats.fixed_clearance, o.stats.clearance_rounds);
  EXPECT_EQ(p.stats.fixed_clearance, 0u);
  EXPECT_GT(o.stats.fixed_clearance, 0u);
  EXPECT_TRUE(o.stats.converged);
  // Measured: 101 and 25 with the default feature zone (22 before the snap's later
  // passes took a narrowed kernel; 92 and 15 without a zone; vertices blended
  // between a held agent and a free one).
  EXPECT_GT(p.inside, 50u);
  EXPECT_LT(o.inside * 4, p.inside);
  // The profiles still keep their shape (the held-out slices: the test above).
  for (const double phi : {0.0, std::numbers::pi})
    EXPECT_LT(10.0 * profile_error(o, o.result, phi), profile_error(o, o.warped, phi)) << phi;
}

TEST(SurfaceDress, SameBodyGivesTheInputBackAndThreadsDoNotMatter) {
  // A = B and the features at their original places: the output is the input.
  const Case same = run_dress(false, 6000, {}, true);
  const double scale = same.dress.positions.cwiseAbs().maxCoeff();
  EXPECT_LT((same.result - same.dress.positions).cwiseAbs().maxCoeff(), 1e-6 * scale);
  // 1 and 2 threads, coarse levels and all: the same bytes.
  Case one, two;
  {
    const ThreadLimit limit(1);
    one = run_dress(false);
  }
  {
    const ThreadLimit limit(2);
    two = run_dress(false);
  }
  EXPECT_GE(one.stats.levels, 2);
  ASSERT_EQ(one.result.rows(), two.result.rows());
  EXPECT_EQ(std::memcmp(one.result.data(), two.result.data(), sizeof(double) * one.result.size()), 0);
}

// Eq. 14 for the vertices asks whether each is within epsilon of body B or
// inside it; apply(..., body_b) answers with a query of radius epsilon
// (near_body), and must answer as body_distance(p) < epsilon does.
TEST(SurfaceDress, TheNearBodyTestIsTheBodyDistanceUnderEpsilon) {
  const mq::BodyParams a{};
  mq::BodyParams b = a;
  b.belly = 8;
  b.hip = a.hip + 6;
  mq::GarmentParams gp;
  gp.kind = mq::GarmentParams::Kind::Dress;
  gp.target_vertices = 3000;
  gp.ease = -0.5;
  const Garment dress = mq::make_garment(a, gp);
  const BodyMesh body_b = mq::make_body(b);
  const BodySurface surface_b(body_b);
  const SurfaceBinding sb = SurfaceBinding::bind(dress, Points(0, 3), SurfaceOptions{});
  const auto distance = sb.body_distance(surface_b);
  const NearBody near = sb.near_body(surface_b);
  const double eps = SurfaceOptions{}.epsilon;
  // The dress's vertices, body B's vertices moved along their normal by -1.5 to
  // 1.5 epsilon (inside, on, just under and just over epsilon) and far points.
  std::vector<Vec3> points;
  for (Eigen::Index v = 0; v < dress.positions.rows(); ++v) points.push_back(row3(dress.positions, Index(v)));
  for (Eigen::Index v = 0; v < body_b.vertices.rows(); v += 7) {
    const Vec3 p = row3(body_b.vertices, Index(v));
    const Vec3 n = surface_b.closest(p + Vec3(0, 0, 1e-9)).normal;
    for (const double t : {-1.5, -0.5, 0.0, 0.5, 0.999, 1.0, 1.001, 1.5}) points.push_back(p + t * eps * n);
  }
  points.push_back(Vec3(0, 300, 0));
  std::size_t near_count = 0;
  for (const Vec3& p : points) {
    ASSERT_EQ(near(p), distance(p) < eps) << p.transpose();
    near_count += near(p);
  }
  EXPECT_GT(near_count, points.size() / 4);
  EXPECT_LT(near_count, points.size());
}

TEST(SurfaceDress, MultigridCyclesReachThePlainSweepsFixedPointInFarFewerSweeps) {
  // V-cycles (aggregation coarse levels) against the paper's plain sweeps run
  // until they converge: the same fixed point, in a fraction of the sweeps.
  // Eq. 14 (band 0): the band's holds are an active set that the first, loose
  // solve decides, so the two solvers may hold different agents (3e-2 cm apart).
  SurfaceOptions eq14;
  eq14.near_body_band = 0.0;
  SurfaceOptions plain = eq14;
  plain.multigrid = false;
  plain.max_iterations = 20000;
  const Case p = run_dress(false, 6000, plain);
  const Case m = run_dress(false, 6000, eq14);
  std::printf("  plain sweeps: %d (update %.2e); multigrid: %d (update %.2e)\n", p.stats.iterations, p.stats.final_update,
              m.stats.iterations, m.stats.final_update);
  ASSERT_TRUE(p.stats.converged);
  ASSERT_TRUE(m.stats.converged);
  EXPECT_LT(m.stats.iterations * 10, p.stats.iterations);
  const double diff = (m.result - p.result).cwiseAbs().maxCoeff();
  std::printf("  largest vertex difference %.2e cm\n", diff);
  EXPECT_LT(diff, 0.01);
}

TEST(SurfaceDress, KrylovCyclesConvergeWhereBareCyclesSlowDown) {
  // 5x the default agent budget, on a 150k dress: bare V-cycles slow down (their
  // residual reduction per cycle degrades with the agent count), BiCGSTAB
  // preconditioned by one V-cycle does not. Both against a direct solution of
  // the same captured system (eq. 13 on the free agents, fixed ones as data).
  SurfaceOptions so;
  so.agent_budget = 100000;
  run_dress(false, 150000, so, false, false, [&](const SurfaceBinding& sb, const SurfaceSystem& sys) {
    const std::size_t n = sb.agent_count();
    ASSERT_GT(n, 80000u);
    // Direct: A x = b on the free agents.
    const AgentRows& rows = sb.rows();
    std::vector<Eigen::Index> var(n, -1);
    Eigen::Index m = 0;
    for (std::size_t a = 0; a < n; ++a)
      if (sys.free[a]) var[a] = m++;
    std::vector<Eigen::Triplet<double>> t;
    Eigen::MatrixXd b(m, 3);
    for (std::size_t a = 0; a < n; ++a) {
      if (var[a] < 0) continue;
      t.emplace_back(var[a], var[a], rows.diag[a]);
      b.row(var[a]) = sys.h.row(Eigen::Index(a));
      for (Index k = rows.ring.offsets[a]; k < rows.ring.offsets[a + 1]; ++k) {
        const Index j = rows.ring.indices[k];
        if (var[j] >= 0) t.emplace_back(var[a], var[j], -rows.weight[k]);
        else b.row(var[a]) += rows.weight[k] * sys.start.row(Eigen::Index(j));
      }
    }
    Eigen::SparseMatrix<double> a(m, m);
    a.setFromTriplets(t.begin(), t.end());
    Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(a);
    ASSERT_EQ(lu.info(), Eigen::Success);
    const Eigen::MatrixXd direct = lu.solve(b);
    auto error = [&](const Points& x) {
      double worst = 0.0;
      for (std::size_t k = 0; k < n; ++k)
        if (var[k] >= 0) worst = std::max(worst, (x.row(Eigen::Index(k)) - direct.row(var[k])).cwiseAbs().maxCoeff());
      return worst;
    };
    const SolveOptions o{500, 1e-5, 1.0};  // the pipeline's budget
    Points xv = sys.start, xk = sys.start;
    int krylov = 0;
    const SolveReport v = sb.solve(sys.h, sys.free, xv, o, FineSolver::v_cycles);
    const SolveReport k = sb.solve(sys.h, sys.free, xk, o, FineSolver::krylov, &krylov);
    std::printf("  %zu agents: V-cycles %d sweeps (converged %d), error %.2e; BiCGSTAB %d iterations, %d sweeps, error %.2e\n",
                n, v.iterations, v.converged, error(xv), krylov, k.iterations, error(xk));
    // Measured: V-cycles not converged after 500 sweeps (nor after 5,000), 1e-2 from
    // the direct solution; BiCGSTAB 17 iterations, 69 sweeps, 4e-5 from it.
    ASSERT_TRUE(k.converged);
    EXPECT_GT(krylov, 0);
    EXPECT_LT(5 * k.iterations, v.iterations);
    EXPECT_LT(error(xk), 1e-3);
    EXPECT_LT(10.0 * error(xk), error(xv));
  });
}

TEST(SurfaceDress, TheRmsToleranceScalesTheL2RuleBySqrtOfTheFreeAgents) {
  SurfaceOptions so;
  so.tolerance_rms = 1e-7;
  const Case c = run_dress(false, 6000, so);
  const double free_agents = double(c.stats.agents - c.stats.fixed_body - c.stats.fixed_feature - c.stats.fixed_clearance -
                                    c.stats.anchored);
  std::printf("  RMS 1e-7 over %.0f free agents: L2 tolerance %.3e, final update %.3e after %d sweeps\n", free_agents,
              c.stats.tolerance, c.stats.final_update, c.stats.iterations);
  EXPECT_NEAR(c.stats.tolerance, 1e-7 * std::sqrt(free_agents), 1e-12);
  EXPECT_TRUE(c.stats.converged);
  EXPECT_LT(c.stats.final_update, c.stats.tolerance);
  EXPECT_EQ(run_dress(false, 6000).stats.tolerance, 1e-5);  // off: the paper's L2 rule
}

}  // namespace
}  // namespace refit
