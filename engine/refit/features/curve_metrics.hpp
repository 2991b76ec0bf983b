#pragma once
// How well a curve kept its shape (the report's numbers for section 4).
#include <refit/core/types.hpp>

namespace refit {

/// RMS distance between `curve` and `original` (same number of rows, row i
/// corresponds to row i) after the best similarity alignment of the original
/// onto the curve (rotation, uniform scale, translation; Umeyama), divided by
/// the original's polyline length (closed: including the closing edge). 0 for
/// a similar copy. Throws refit::Error when the row counts differ, there are
/// fewer than 2 rows, or the original has zero length.
double shape_error(const Points& curve, const Points& original, bool closed);

/// Scale of the best similarity (Umeyama) carrying `original` onto `curve`
/// (same row count, at least 2 rows): how much the curve grew (> 1) or shrank.
double similarity_scale(const Points& original, const Points& curve);

/// Mean absolute change, in degrees, of the turning angle between consecutive
/// segments (the unsigned 3D angle between edge i-1 -> i and edge i -> i+1) from
/// `original` to `curve`. Closed curves wrap. Zero-length edges count as no turn.
/// Throws refit::Error when the row counts differ or there are fewer than 3 rows.
double turning_angle_change_deg(const Points& curve, const Points& original, bool closed);

}  // namespace refit
