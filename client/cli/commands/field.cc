// `geodex field`: the distance from the nearest source to every mesh vertex,
// or with --radius R the exact distance of every vertex within R (one exact
// propagation on the server, whose cost follows the vertices it reaches).
//
// `field --out X.ply` asks for the distance field, then for the mesh of the
// version that answered it (GetMesh pinned to that version, so that both
// come from the same index even if the model is reloaded in between), and
// writes the mesh colored by distance with the distance as the vertex
// quality; unreachable vertices are gray with quality -1 (FieldToPly in
// client/cli/outputs.h).

#include <cmath>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/outputs.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct FieldFlags {
  ConnectionFlags conn;
  ModelFlags model;
  std::string sources, out = "-";
  bool nearest = false;
  double radius = 0;  // 0: every vertex
};

// The mesh the distance field `field` was computed on: GetMesh pinned to the
// version that answered the field, so that a model reloaded between the two
// calls cannot pair one version's distances with another's mesh.
absl::StatusOr<Mesh> MeshOfField(const Client& client, const ModelFlags& model,
                                 int64_t field_version, size_t field_vertices, bool within_radius) {
  const int64_t version = field_version != 0 ? field_version : model.version;
  absl::StatusOr<Mesh> mesh = client.GetMesh(ModelRef(model.name, version));
  if (!mesh.ok()) {
    return absl::Status(mesh.status().code(),
                        absl::StrFormat("the mesh of model '%s' version %d (the version that "
                                        "answered the distance field): %s",
                                        model.name, version, mesh.status().message()));
  }
  if (version != 0 && mesh->version != version) {
    return absl::DataLossError(absl::StrFormat(
        "the server sent the mesh of version %d for the distance field of version %d",
        mesh->version, version));
  }
  if (within_radius ? field_vertices > mesh->positions.size()
                    : field_vertices != mesh->positions.size()) {
    return absl::DataLossError(
        absl::StrFormat("the distance field has %d vertices but the mesh of version %d has %d",
                        field_vertices, mesh->version, mesh->positions.size()));
  }
  return mesh;
}

absl::Status Field(const FieldFlags& flags) {
  const bool ply = absl::EndsWithIgnoreCase(flags.out, ".ply");
  if (ply && flags.nearest) {
    return InputError(absl::InvalidArgumentError(
        "--nearest is for text output; a .ply holds the distances and colors only"));
  }
  absl::StatusOr<Client> client = MakeClient(flags.conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<std::vector<SurfacePoint>> sources =
      LoadPoints(*client, flags.model.ref(), flags.sources);
  if (!sources.ok()) return sources.status();
  if (sources->empty()) {
    return InputError(absl::InvalidArgumentError(
        absl::StrCat(flags.sources, ": no source points (lines 'f w0 w1 w2')")));
  }
  if (flags.radius != 0) {
    if (!(std::isfinite(flags.radius) && flags.radius > 0)) {
      return InputError(absl::InvalidArgumentError(
          absl::StrFormat("--radius must be finite and > 0, got %g", flags.radius)));
    }
    absl::StatusOr<VertexDistancesWithin> field =
        client->DistanceFieldWithin(flags.model.ref(), *sources,
                                    {.radius = flags.radius, .with_nearest_source = flags.nearest});
    if (!field.ok()) return field.status();
    if (!ply) return WriteFileOrStdout(flags.out, FieldWithinToText(*field));
    const size_t reached = field->vertices.empty() ? 0 : field->vertices.back() + size_t{1};
    absl::StatusOr<Mesh> mesh = MeshOfField(*client, flags.model, field->version, reached, true);
    if (!mesh.ok()) return mesh.status();
    return WriteFileOrStdout(flags.out,
                             FieldToPly(*mesh, DenseDistances(*field, mesh->positions.size())));
  }
  absl::StatusOr<VertexDistances> field =
      client->DistanceField(flags.model.ref(), *sources, flags.nearest);
  if (!field.ok()) return field.status();
  if (!ply) return WriteFileOrStdout(flags.out, FieldToText(*field));
  absl::StatusOr<Mesh> mesh =
      MeshOfField(*client, flags.model, field->version, field->distances.size(), false);
  if (!mesh.ok()) return mesh.status();
  return WriteFileOrStdout(flags.out, FieldToPly(*mesh, field->distances));
}

}  // namespace

void AddFieldCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<FieldFlags>();
  CLI::App* field = app->add_subcommand(
      "field",
      "Distance from the nearest source to every mesh vertex: one line per vertex, or with "
      "--out X.ply the model's mesh colored by distance. With --radius R, the exact distance "
      "of every vertex within R only: one line 'vertex distance' per such vertex, ascending");
  AddConnectionFlags(field, &flags->conn);
  AddModelFlags(field, &flags->model);
  field->add_option("--sources", flags->sources, "File of lines 'f w0 w1 w2'")->required();
  field
      ->add_option("--radius", flags->radius,
                   "Only the vertices within this geodesic distance of the sources (mesh units; "
                   "finite, > 0), with exact distances: text lines 'vertex distance' (with "
                   "--nearest 'vertex distance source'), vertices ascending, none beyond R; a .ply "
                   "draws the vertices beyond R gray with quality -1. 0 (default): every vertex")
      ->capture_default_str();
  field->add_flag("--nearest", flags->nearest,
                  "Also print the index of the nearest source on each line (text output only)");
  field
      ->add_option("-o,--out", flags->out,
                   "Output file ('-': standard output). Text, one distance per vertex ('inf': "
                   "unreachable); a name ending in .ply gets an ASCII PLY of the mesh (of the "
                   "version that answered) for MeshLab: per vertex x y z, a color (dark purple "
                   "at the sources to yellow at the farthest vertex) and quality = distance; "
                   "unreachable vertices are gray (128 128 128) with quality -1")
      ->capture_default_str();
  field->callback([flags, status] { *status = Field(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(50, AddFieldCommand);

}  // namespace geodex::client::cli
