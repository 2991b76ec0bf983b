#pragma once
// A sheet (sheet.hpp) as SVG at true scale: the document's width and height
// carry the unit (cm or mm) and one user unit of the viewBox is one of them, so
// a printer or a cutter plots the pieces at their size. Layers become groups
// named after them; fills come first, then lines, then texts.
#include <refit/patterns/sheet.hpp>

#include <string>

namespace refit {

/// The SVG text of `sheet`, whose coordinates are garment units of
/// `cm_per_unit` centimetres each, in `units` ("cm" or "mm"; refit::Error otherwise).
std::string sheet_svg(const Sheet& sheet, double cm_per_unit, const std::string& units = "cm");

}  // namespace refit
