// read_mesh / write_mesh: whole-file reads with a size limit, format dispatch, and atomic
// writes (temporary file in the same directory, then rename).
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <system_error>

#include "csculpt/io.h"
#include "io_detail.h"

namespace csculpt {
namespace {

using io_detail::cat;

// Mesh files beyond this are not sculpting inputs; refusing them keeps a mistaken path (a
// disk image, a video) from exhausting memory.
constexpr std::uint64_t kMaxFileBytes = std::uint64_t{2} << 30;

std::string errno_message(int err) {
  return std::error_code(err, std::generic_category()).message();
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

std::string extension_of(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  for (char& c : ext) {
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return ext;
}

bool is_known_extension(const std::string& ext) {
  return ext == "ply" || ext == "obj" || ext == "off" || ext == "stl";
}

bool starts_with_ci(std::string_view s, std::string_view prefix) {
  if (s.size() < prefix.size()) return false;
  for (std::size_t i = 0; i < prefix.size(); ++i) {
    char c = s[i];
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    if (c != prefix[i]) return false;
  }
  return true;
}

// Format from content, for files without a known extension.
std::string sniff(std::string_view bytes) {
  if (bytes.starts_with("ply\n") || bytes.starts_with("ply\r")) return "ply";
  if (bytes.size() >= 84) {
    std::uint64_t n = 0;
    for (int i = 3; i >= 0; --i) {
      n = (n << 8) | static_cast<unsigned char>(bytes[80 + static_cast<std::size_t>(i)]);
    }
    if (84 + 50 * n == bytes.size()) return "stl";
  }
  std::string_view rest = bytes;
  const std::string_view first = io_detail::next_token(rest);
  if (first.ends_with("OFF") && first.size() <= 6) return "off";
  if (starts_with_ci(first, "solid")) return "stl";
  // OBJ has no magic: look for a vertex line.
  std::size_t pos = 0;
  while (pos < bytes.size()) {
    std::size_t nl = bytes.find('\n', pos);
    if (nl == std::string_view::npos) nl = bytes.size();
    std::string_view line = io_detail::trim(bytes.substr(pos, nl - pos));
    if (line.size() > 2 && line[0] == 'v' && io_detail::is_space(line[1])) return "obj";
    pos = nl + 1;
  }
  return {};
}

/// Appends what `f` holds to `bytes`, in chunks rather than trusting a size: the file may be
/// a pipe or change. The buffer never grows past the limit (plus a chunk), and a stream whose
/// first chunk is not recognisably a mesh (zeros or random bytes piped in) is refused at once
/// rather than read for gigabytes.
void read_chunks(std::FILE* f, const std::string& path, bool stream, std::string& bytes) {
  constexpr std::size_t kChunk = std::size_t{1} << 20;
  for (;;) {
    const std::size_t old = bytes.size();
    if (bytes.capacity() < old + kChunk) {
      bytes.reserve(std::min<std::size_t>(std::max(2 * bytes.capacity(), old + kChunk),
                                          kMaxFileBytes + kChunk));
    }
    bytes.resize(old + kChunk);
    const std::size_t got = std::fread(bytes.data() + old, 1, kChunk, f);
    bytes.resize(old + got);
    if (bytes.size() > kMaxFileBytes) {
      throw InvalidInput(cat(path, ": file is more than the 2 GiB limit"));
    }
    if (got < kChunk) {
      if (std::ferror(f)) throw IoError(cat(path, ": read error: ", errno_message(errno)));
      return;
    }
    if (stream && old == 0 && !is_known_extension(extension_of(path)) && sniff(bytes).empty()) {
      throw InvalidInput(cat(path, ": not a regular file, and its first ", bytes.size(),
                             " bytes are not a mesh file"));
    }
  }
}

std::string read_file(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) {
    throw IoError(cat(path, ": cannot open: ", ec ? ec.message() : "no such file"));
  }
  if (std::filesystem::is_directory(status)) throw IoError(cat(path, ": is a directory"));
  if (std::filesystem::is_character_file(status) || std::filesystem::is_block_file(status)) {
    // /dev/zero, /dev/urandom, a disk: endless or huge, never a mesh; pipes are read.
    throw InvalidInput(cat(path, ": is a device, not a mesh file"));
  }
  std::uintmax_t expected = 0;
  if (std::filesystem::is_regular_file(status)) {
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxFileBytes) {
      throw InvalidInput(cat(path, ": file is ", size, " bytes, more than the 2 GiB limit"));
    }
    if (!ec) expected = size;
  }
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "rb"));
  if (!f) throw IoError(cat(path, ": cannot open: ", errno_message(errno)));
  std::string bytes;
  // One chunk of slack so that reading up to the expected size does not reallocate.
  bytes.reserve(static_cast<std::size_t>(expected) + (std::size_t{1} << 20));
  read_chunks(f.get(), path, !std::filesystem::is_regular_file(status), bytes);
  return bytes;
}

void write_atomically(const std::string& path, std::string_view data) {
  // Unique per process and call, so concurrent writers of the same path cannot collide on
  // the temporary; the final rename is atomic on POSIX.
  static std::atomic<std::uint64_t> counter{0};
  const std::string temp = cat(path, ".tmp.", ::getpid(), ".", counter.fetch_add(1));
  std::FILE* f = std::fopen(temp.c_str(), "wb");
  if (!f) throw IoError(cat(path, ": cannot create ", temp, ": ", errno_message(errno)));
  bool ok = std::fwrite(data.data(), 1, data.size(), f) == data.size();
  int err = ok ? 0 : errno;
  if (ok && std::fflush(f) != 0) {
    ok = false;
    err = errno;
  }
  if (ok && ::fsync(::fileno(f)) != 0) {
    ok = false;
    err = errno;
  }
  if (std::fclose(f) != 0 && ok) {
    ok = false;
    err = errno;
  }
  if (ok && std::rename(temp.c_str(), path.c_str()) != 0) {
    ok = false;
    err = errno;
  }
  if (!ok) {
    std::remove(temp.c_str());
    throw IoError(cat(path, ": cannot write: ", errno_message(err)));
  }
}

Mesh read_format(const std::string& path, Faces faces) {
  const std::string bytes = read_file(path);
  std::string format = extension_of(path);
  if (!is_known_extension(format)) {
    if (bytes.empty()) throw InvalidInput(cat(path, ": file is empty"));
    format = sniff(bytes);
  }
  if (format == "ply") return parse_ply(bytes, path, faces);
  if (format == "obj") return parse_obj(bytes, path, faces);
  if (format == "off") return parse_off(bytes, path, faces);
  if (format == "stl") return parse_stl(bytes, path, faces);
  throw InvalidInput(cat(path, ": unrecognised file format (supported: .ply .obj .off .stl)"));
}

}  // namespace

namespace io_detail {

void check_parsed(const Mesh& mesh, std::string_view what, Faces faces) {
  if (!(faces == Faces::optional && mesh.triangles.empty())) check_unreferenced(mesh, what);
  validate(mesh, what, faces);
}

}  // namespace io_detail

Mesh read_mesh(const std::string& path, Faces faces) {
  try {
    return read_format(path, faces);
  } catch (const OutOfMemory&) {
    throw;
  } catch (const std::bad_alloc&) {
    // Whatever was allocated is freed by now, so the message can be built.
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    throw OutOfMemory(ec ? cat(path, ": out of memory reading it")
                         : cat(path, ": out of memory reading its ", size, " bytes"));
  }
}

void write_mesh(const Mesh& mesh, const std::string& path) {
  const std::string format = extension_of(path);
  std::string data;
  if (format == "ply") {
    data = io_detail::encode_ply(mesh, path);
  } else if (format == "obj") {
    data = io_detail::encode_obj(mesh, path);
  } else {
    throw InvalidInput(cat(path, ": cannot write '.", format, "' files (write .ply or .obj)"));
  }
  write_atomically(path, data);
}

}  // namespace csculpt
