// csculpt-app: argument parsing only; the app lives in app.cpp.
#include <cstdio>

#include "app.h"
#include "options.h"

int main(int argc, char** argv) {
  ParseResult parsed = parse_options(argc, argv);
  if (!parsed.options) {
    std::fputs(parsed.message.c_str(), parsed.exit_code == 0 ? stdout : stderr);
    return parsed.exit_code;
  }
  return run_app(*parsed.options);
}
