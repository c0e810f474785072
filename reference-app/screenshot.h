// The window's back buffer as a PNG (glReadPixels + stb_image_write).
#pragma once

#include <string>

bool write_screenshot(const std::string& path, int width, int height, std::string& error);
