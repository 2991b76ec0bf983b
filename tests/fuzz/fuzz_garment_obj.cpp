// libFuzzer target: the garment OBJ reader on arbitrary bytes. A file it accepts
// must write back and read again to the same counts and positions.
#include <refit/core/error.hpp>
#include <refit/io/obj_garment.hpp>

#include <cstdint>
#include <cstdlib>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  refit::Garment g;
  try {
    g = refit::parse_garment_obj(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.obj");
  } catch (const refit::Error&) {
    return 0;  // refused with a message: what bad input should get
  }
  std::string text;
  try {
    text = refit::format_garment_obj(g);
  } catch (const refit::Error&) {
    return 0;  // e.g. a position that cannot be written faithfully
  }
  const refit::Garment again = refit::parse_garment_obj(text, "fuzz-again.obj");
  if (again.positions.rows() != g.positions.rows() || again.faces.rows() != g.faces.rows() ||
      !(again.positions.array() == g.positions.array()).all())
    std::abort();  // the round trip lost or changed something
  return 0;
}
