#pragma once

// Output formats of the `geodex` CLI.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geodex/client/types.h"

namespace geodex::client::cli {

// Paths as Wavefront OBJ: all points as `v` lines, one `l` polyline per path
// (a path of a single point gets a `p` point element).
std::string PathsToObj(const std::vector<GeodesicPath>& paths);

// Paths as ASCII PLY: vertices (x, y, z, path index) and edges between
// consecutive points of a path.
std::string PathsToPly(const std::vector<GeodesicPath>& paths);

// Paths as JSON: [{"length": L, "points": [{"face": f, "w": [..], "xyz": [..]}, ...]}, ...].
std::string PathsToJson(const std::vector<GeodesicPath>& paths);

// A distance field as text: one line per vertex, "distance" or, with
// nearest sources, "distance nearest_source".
std::string FieldToText(const VertexDistances& field);

// A distance field within a radius as text: one line per vertex within it,
// ascending, "vertex distance" or, with nearest sources, "vertex distance
// nearest_source".
std::string FieldWithinToText(const VertexDistancesWithin& field);

// The field within a radius over every one of `num_vertices` vertices:
// +infinity beyond the radius (what FieldToPly draws gray). Vertices past
// the end are ignored.
std::vector<double> DenseDistances(const VertexDistancesWithin& field, size_t num_vertices);

// An ASCII PLY of `mesh` (vertices x y z, triangles) colored by a distance
// field, for MeshLab and the like. Each vertex has the color RampColor(d /
// largest finite distance), dark purple at the sources to yellow at the
// farthest vertex, and the distance as its `quality` (MeshLab shows and
// filters on it). Vertices with no finite distance (on another connected
// component than every source, or unreferenced) are kUnreachableColor, a gray
// the ramp never takes, with quality -1, since a PLY float cannot hold
// infinity. Requires distances.size() == mesh.positions.size().
std::string FieldToPly(const Mesh& mesh, const std::vector<double>& distances);

// The color FieldToPly gives vertices with no finite distance.
inline constexpr std::array<uint8_t, 3> kUnreachableColor = {128, 128, 128};

// The color of t in [0, 1] on the ramp FieldToPly uses.
std::array<uint8_t, 3> RampColor(double t);

// One line per model: name, version, state, vertices, faces, samples.
std::string ModelsTable(const std::vector<ModelInfo>& models);

// A model's full description as JSON: ModelInfo's fields under their proto
// names, and the build report's JSON (report_json) as "report" when the
// server sent it.
std::string ModelToJson(const ModelInfo& model);

// `s` as a JSON string literal, quotes included.
std::string JsonString(const std::string& s);

}  // namespace geodex::client::cli
