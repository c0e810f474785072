#include "screenshot.h"

#include <epoxy/gl.h>
#include <stb_image_write.h>

#include <cstring>
#include <vector>

bool write_screenshot(const std::string& path, int width, int height, std::string& error) {
  std::vector<unsigned char> pixels(size_t(width) * height * 3), flipped(pixels.size());
  glReadBuffer(GL_BACK);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, pixels.data());
  const size_t row = size_t(width) * 3;
  for (int y = 0; y < height; ++y)  // OpenGL's rows run bottom-up, PNG's top-down
    std::memcpy(&flipped[y * row], &pixels[(height - 1 - y) * row], row);
  if (!stbi_write_png(path.c_str(), width, height, 3, flipped.data(), static_cast<int>(row))) {
    error = "cannot write the screenshot " + path;
    return false;
  }
  return true;
}
