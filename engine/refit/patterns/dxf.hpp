#pragma once
// A sheet (sheet.hpp) as DXF (AutoCAD R12 ASCII, which every CAD and cutting
// program reads), written by hand: the standard entities need no library.
// Closed outlines are closed POLYLINEs, open lines open ones, each on its
// sheet layer (CUT, FEATURES, GRAIN); texts are TEXT on layer TEXT; fills are
// left out. Coordinates stay in the garment's units, named in the header
// ($INSUNITS), y up as on the sheet.
#include <refit/patterns/sheet.hpp>

#include <string>

namespace refit {

/// The DXF text of `sheet`; `units` are the garment's (cm, mm, m or in;
/// refit::Error otherwise).
std::string sheet_dxf(const Sheet& sheet, const std::string& units);

}  // namespace refit
