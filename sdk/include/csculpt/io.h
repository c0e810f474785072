// Reading and writing mesh files: PLY (ascii and binary, with channels as vertex
// properties), OBJ, OFF and STL (read).
#pragma once

#include <string>
#include <string_view>

#include "csculpt/mesh.h"

namespace csculpt {

/// Reads a triangle mesh; the format is chosen by the file's contents/extension
/// (.ply .obj .off .stl, case-insensitive). Polygons are fan-triangulated.
/// PLY vertex properties other than x,y,z become channels: `name` (width 1) or
/// `name_r/_g/_b/_a` (width 2..4); colour `red/green/blue` becomes albedo.
/// Throws IoError (cannot open), InvalidInput (malformed; the message names the file,
/// the line or element and the problem) or OutOfMemory (naming the file). Never returns a mesh that
/// fails validate().
///
/// Memory: a reader allocates in proportion to the bytes the file holds (the file itself, then
/// at most a few times its size; counts in a header are checked against the bytes that follow
/// before anything is reserved from them). Files over 2 GiB are refused; so are devices
/// (/dev/zero) and a pipe whose first MiB is not recognisably a mesh. A mesh with more than
/// 1,000,000 vertices that no face uses, when they are also more than half of its vertices,
/// is refused naming the counts: such vertices cost as much as used ones in every later step
/// (a 2 GB sparse file would take 20 GB in a hierarchy) and no one can sculpt them, while
/// exporters' stray vertices are few. Running out of memory throws OutOfMemory (a
/// std::bad_alloc) naming the file.
///
/// Details: a file without a known extension is recognised by its contents. PLY: an `alpha` next to
/// red/green/blue is dropped (albedo is RGB); channel linearisations follow default_linearisation()
/// unless a header line `comment csculpt linearisation <channel> <identity|square|srgb>` says
/// otherwise (the writer adds one when needed); unknown header lines are ignored like comments.
/// STL: corners with bitwise-equal coordinates are welded in order of first occurrence, and
/// zero-area facets (two equal corners) are dropped, as STL exporters emit them routinely.
///
/// With `faces` optional, a file without faces reads as the positions (and channels) it holds:
/// a point set such as an ideal result stored without its base's faces.
Mesh read_mesh(const std::string& path, Faces faces = Faces::required);

/// Writes .ply (binary little-endian, channels as float properties) or .obj (positions and
/// faces only). Writes to a temporary file and renames it, so a failure leaves no partial file.
/// Throws InvalidInput if the mesh fails validate() or its channel names would not read back
/// as the same channels from PLY (e.g. width-1 channels "red", "green", "blue"), IoError if
/// the file cannot be written. Reading a written PLY gives back a bit-identical mesh.
void write_mesh(const Mesh& mesh, const std::string& path);

/// Parses PLY bytes held in memory (what read_mesh does for .ply); `what` names the source
/// in error messages. Exposed for fuzzing.
Mesh parse_ply(std::string_view bytes, std::string_view what, Faces faces = Faces::required);
Mesh parse_obj(std::string_view bytes, std::string_view what, Faces faces = Faces::required);
Mesh parse_off(std::string_view bytes, std::string_view what, Faces faces = Faces::required);
Mesh parse_stl(std::string_view bytes, std::string_view what, Faces faces = Faces::required);

}  // namespace csculpt
