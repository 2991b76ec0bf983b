#pragma once
// Procedural mannequins and garments: the built-in example (`refit demo`) and the
// fixture generator of every test suite and benchmark. Deterministic (no random
// numbers, no thread-count dependence) and fast.
//
// Conventions as the real data: cm, +Y up, the body faces +Z, +X is the body's
// left, soles at y = 0.
//
// The body is five closed lofted tubes (torso with neck and head, two legs, two
// arms) that do not touch each other: each ring is a horizontal (or, for the
// arms, axis-normal) star-shaped curve and ring positions are strictly monotone
// along the tube, so no tube intersects itself. Every BodyParams at one
// resolution gives the same vertex count and triangle list, so bodies made from
// two parameter sets are an A/B pair.
#include <refit/body/body_mesh.hpp>
#include <refit/core/garment.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace refit::mannequin {

struct BodyParams {
  double height = 165;   // cm, soles to the top of the head
  double bust = 88;      // girth (tape measure, convex hull perimeter) at the bust level
  double waist = 68;     // girth at the waist level
  double hip = 96;       // girth at the hip level (hip also deepens the buttocks and thickens the legs)
  double belly = 0;      // extra forward bulge in cm at the navel, smooth (Gaussian) around it
  double shoulder = 38;  // shoulder width in cm (torso width at the shoulder level)
  int resolution = 1;    // 1: about 26k triangles; n: about n*n times as many
};

/// Heights (y, cm) of the body's levels; the torso axis is x = 0, z = 0.
struct Landmarks {
  double ankle = 0, knee = 0, crotch = 0, hip = 0, navel = 0, waist = 0, bust = 0,
         armpit = 0, shoulder = 0, neck = 0, height = 0;
};

/// Throws refit::Error ("mannequin: ...") when a parameter is out of its sane
/// range (height 100..250, girths 30..250, belly 0..40, shoulder 20..70,
/// resolution 1..8) or the shape would be inconsistent (waist > hip + 40, ...).
void check_params(const BodyParams& p);

/// The levels of the body made from p. Throws as check_params.
Landmarks landmarks(const BodyParams& p);

/// Analytic shape of the body (the smooth surface the mesh samples). Used by the
/// garment generator to stay outside the body, and by tests.
class BodyShape {
 public:
  /// Throws as check_params.
  explicit BodyShape(const BodyParams& p);

  /// Torso cross-section at height y: two half ellipses sharing the half width a
  /// (front depth bf, back depth bb) about the axis x = z = 0, plus the belly bump
  /// (amplitude `bump` at the front centre). Zero size outside [crotch, height].
  struct TorsoSection {
    double a = 0, bf = 0, bb = 0, bump = 0;
  };
  TorsoSection torso(double y) const;
  /// Distance from the torso axis to the torso surface at height y in the
  /// horizontal direction (cos phi, sin phi) = (x, z) (phi = pi/2 is the front).
  static double radius(const TorsoSection& s, double cos_phi, double sin_phi);

  /// Left leg cross-section at height y: ellipse centred (xc, zc), half axes rx
  /// (along x), rz (along z); the right leg is its mirror (x -> -x). Zero size
  /// outside [0, leg top].
  struct LegSection {
    double xc = 0, zc = 0, rx = 0, rz = 0;
  };
  LegSection leg(double y) const;
  double leg_top() const { return leg_top_; }

  /// Largest distance from the torso axis to the body (torso and both legs; the
  /// arms are left out: they hang well away) at height y in direction
  /// (cos phi, sin phi). 0 where nothing is hit.
  double extent(double y, double cos_phi, double sin_phi) const;

  const Landmarks& levels() const { return levels_; }
  const BodyParams& params() const { return params_; }

 private:
  // Profile keys: values at a height, blended with smoothstep in between so
  // every key is a stationary point (the girth levels are exact extrema).
  struct Key {
    double y;
    double v[4];
  };
  static void interpolate(const std::vector<Key>& keys, double y, double out[4]);

  BodyParams params_;
  Landmarks levels_;
  std::vector<Key> torso_keys_, leg_keys_;
  double leg_top_ = 0, torso_cap_bottom_ = 0, torso_cap_top_ = 0, leg_cap_top_ = 0, leg_cap_bottom_ = 0;
  double navel_sigma_ = 0;
};

/// The mannequin as a closed, watertight, outward-oriented triangle mesh: about
/// 26k triangles at resolution 1 (resolution^2 times as many above). The same
/// resolution always gives the same vertex count and triangle list.
/// Throws refit::Error on bad parameters (see check_params).
BodyMesh make_body(const BodyParams& p);

struct GarmentParams {
  enum class Kind { Dress, Top, Trousers } kind = Kind::Dress;
  double ease = 0;                     // extra room in cm added to the kind's own ease
  std::size_t target_vertices = 20000; // the vertex count lands within 10% of it (1000 .. 50M)
  bool soup = false;                   // the same surface as messy, non-manifold CAD data
  bool two_layers = false;             // two layers in one garment (see make_garment)
};

/// A quad-mesh garment around the body made from `body` (source = nullptr).
/// - Dress: bodice 1.5 cm over the body from under the arms to the waist, then an
///   A-line skirt with straight side and front/back profiles to a hem at the knee.
/// - Top: 0.8 cm over the body from the base of the neck to just below the hip.
/// - Trousers: waist to ankles, 1.2 cm over the body, two legs joined at a crotch seam.
/// `ease` adds to those. two_layers: the dress gets an under-layer (the dress made
/// with 1 cm less ease, listed first); top and trousers get an over-layer with 1 cm
/// more ease (listed second). soup: patches with duplicated seam vertices, a patch
/// of independent triangles, a flap making an edge non-manifold, two hanging `l`
/// drawstrings from the hem, `p` buttons on the front and one unreferenced vertex;
/// apart from the flap, the drawstrings and the buttons the surface is exactly
/// that of the manifold garment.
/// Throws refit::Error on bad parameters.
Garment make_garment(const BodyParams& body, const GarmentParams& g);

/// The dress's feature file (JSON, cm): left, right, front and back profiles
/// (slices of the dress by the planes z = 0 and x = 0, from the waist to the
/// hem) and the hem (boundary loop). Matches make_garment(body, g) for a dress
/// (the outer layer when two_layers). Throws refit::Error when g is not a dress.
std::string dress_features_json(const BodyParams& body, const GarmentParams& g);

}  // namespace refit::mannequin
