// libFuzzer target: the body readers (OBJ, PLY, OFF, STL) on arbitrary bytes.
// The first byte picks the format; the rest is the file (read_body reads paths).
#include <refit/core/error.hpp>
#include <refit/io/body_io.hpp>

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kExt[] = {".obj", ".ply", ".off", ".stl"};
  const std::string path = "/tmp/refit-fuzz-body-" + std::to_string(getpid()) + kExt[data[0] % 4];
  {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data + 1), static_cast<std::streamsize>(size - 1));
  }
  try {
    const refit::BodyMesh body = refit::read_body(path);
    for (const auto& t : body.triangles)
      for (refit::Index v : t)
        if (v < 0 || v >= body.vertices.rows()) std::abort();  // check_body must have refused it
  } catch (const refit::Error&) {
  }
  std::remove(path.c_str());
  return 0;
}
