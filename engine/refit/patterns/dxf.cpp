// DXF (R12 ASCII) output of a sheet; see dxf.hpp. A DXF file is pairs of lines:
// a group code, then its value.
#include <refit/patterns/dxf.hpp>

#include <refit/core/error.hpp>

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace refit {
namespace {

class DxfWriter {
 public:
  void pair(int code, const std::string& value) { out_ << code << '\n' << value << '\n'; }
  void pair(int code, int value) { out_ << code << '\n' << value << '\n'; }
  void real(int code, double value) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.6f", value);
    pair(code, std::string(buf));
  }
  void point(int code, const Eigen::Vector2d& p) {
    real(code, p.x());
    real(code + 10, p.y());
    real(code + 20, 0.0);
  }
  std::string str() const { return out_.str(); }

 private:
  std::ostringstream out_;
};

// $INSUNITS: 1 inches, 4 millimetres, 5 centimetres, 6 metres.
int insunits(const std::string& units) {
  if (units == "in") return 1;
  if (units == "mm") return 4;
  if (units == "cm") return 5;
  if (units == "m") return 6;
  throw Error("dxf: unknown units '" + units + "'");
}

// AutoCAD colour index of a layer.
int layer_colour(const std::string& layer) {
  if (layer == kCutLayer) return 7;      // white / black
  if (layer == kFeatureLayer) return 1;  // red
  if (layer == kGrainLayer) return 5;    // blue
  return 8;                              // grey
}

}  // namespace

std::string sheet_dxf(const Sheet& sheet, const std::string& units) {
  DxfWriter w;
  const int unit_code = insunits(units);
  std::vector<std::string> layers = {kCutLayer, kFeatureLayer, kGrainLayer, kTextLayer};
  for (const SheetPath& p : sheet.paths)
    if (std::find(layers.begin(), layers.end(), p.layer) == layers.end()) layers.push_back(p.layer);

  w.pair(0, "SECTION");
  w.pair(2, "HEADER");
  w.pair(9, "$ACADVER");
  w.pair(1, "AC1009");
  w.pair(9, "$INSUNITS");
  w.pair(70, unit_code);
  w.pair(9, "$EXTMIN");
  w.point(10, Eigen::Vector2d(0, 0));
  w.pair(9, "$EXTMAX");
  w.point(10, Eigen::Vector2d(sheet.width, sheet.height));
  w.pair(0, "ENDSEC");

  w.pair(0, "SECTION");
  w.pair(2, "TABLES");
  w.pair(0, "TABLE");
  w.pair(2, "LTYPE");
  w.pair(70, 1);
  w.pair(0, "LTYPE");
  w.pair(2, "CONTINUOUS");
  w.pair(70, 0);
  w.pair(3, "Solid line");
  w.pair(72, 65);
  w.pair(73, 0);
  w.real(40, 0.0);
  w.pair(0, "ENDTAB");
  w.pair(0, "TABLE");
  w.pair(2, "LAYER");
  w.pair(70, static_cast<int>(layers.size()));
  for (const std::string& layer : layers) {
    w.pair(0, "LAYER");
    w.pair(2, layer);
    w.pair(70, 0);
    w.pair(62, layer_colour(layer));
    w.pair(6, "CONTINUOUS");
  }
  w.pair(0, "ENDTAB");
  w.pair(0, "ENDSEC");

  w.pair(0, "SECTION");
  w.pair(2, "ENTITIES");
  for (const SheetPath& p : sheet.paths) {
    if (p.points.rows() < 2) continue;
    w.pair(0, "POLYLINE");
    w.pair(8, p.layer);
    w.pair(66, 1);  // vertices follow
    w.point(10, Eigen::Vector2d(0, 0));
    w.pair(70, p.closed ? 1 : 0);
    for (Eigen::Index i = 0; i < p.points.rows(); ++i) {
      w.pair(0, "VERTEX");
      w.pair(8, p.layer);
      w.point(10, p.points.row(i).transpose());
    }
    w.pair(0, "SEQEND");
    w.pair(8, p.layer);
  }
  for (const SheetText& t : sheet.texts) {
    w.pair(0, "TEXT");
    w.pair(8, t.layer);
    w.point(10, t.at);
    w.real(40, t.height);
    w.pair(1, t.text);
    w.pair(72, 1);  // centred on the alignment point
    w.point(11, t.at);
  }
  w.pair(0, "ENDSEC");
  w.pair(0, "EOF");
  return w.str();
}

}  // namespace refit
