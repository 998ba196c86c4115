// `geodex expmap`: the exponential map (geodesic polar coordinates) round a
// point.
//
// It asks for the exponential map round the centre, then for the mesh of the
// version that answered it. --out X.obj writes the patch of faces inside the
// radius with texture coordinates (X.mtl beside it, and a checkerboard
// X_checker.png unless --image names the picture to apply, which is copied
// beside the OBJ); any other --out gets lines "vertex u v". --png renders the
// decal on the whole mesh (client/cli/render.h).

#include <cstdint>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/cli/commands/command.h"
#include "client/cli/commands/command_util.h"
#include "client/cli/decal.h"
#include "client/cli/image.h"
#include "client/cli/render.h"
#include "client/cli/text_io.h"
#include "geodex/client/client.h"

namespace geodex::client::cli {
namespace {

struct ExpMapFlags {
  ConnectionFlags conn;
  ModelFlags model;
  std::string center, out = "-", image, png;
  std::vector<double> direction;
  ExpMapQuery query;
};

// The file name part of a path.
std::string BaseName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

absl::StatusOr<std::string> ReadBinaryFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat("cannot read ", path));
  std::string contents((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return absl::DataLossError(absl::StrCat("cannot read ", path));
  return contents;
}

absl::Status ExpMapCommand(const ExpMapFlags& flags) {
  const bool obj = absl::EndsWithIgnoreCase(flags.out, ".obj");
  if (!flags.image.empty() && !obj) {
    return InputError(absl::InvalidArgumentError("--image is for an --out X.obj decal"));
  }
  absl::StatusOr<ParsedPoints> center = ParsePoints(flags.center);
  if (!center.ok() || center->points.size() != 1) {
    return InputError(absl::InvalidArgumentError(absl::StrFormat(
        "--center wants \"F W0 W1 W2\" (a face id and three weights), got \"%s\"", flags.center)));
  }
  std::string image;
  if (!flags.image.empty()) {
    absl::StatusOr<std::string> read = ReadBinaryFile(flags.image);
    if (!read.ok()) return InputError(read.status());
    image = *std::move(read);
  }
  ExpMapQuery query = flags.query;
  if (!flags.direction.empty()) {
    query.reference_direction =
        Position{flags.direction[0], flags.direction[1], flags.direction[2]};
  }
  if (absl::Status s = CheckDecalRadius(query.radius); !s.ok()) return InputError(s);
  absl::StatusOr<Client> client = MakeClient(flags.conn);
  if (!client.ok()) return client.status();
  absl::StatusOr<int64_t> num_faces = NumFaces(*client, flags.model.ref());
  if (!num_faces.ok()) return num_faces.status();
  if (absl::Status s = CheckPoints("--center", center->points, {1}, *num_faces); !s.ok()) return s;
  absl::StatusOr<ExpMap> map = client->ExpMap(flags.model.ref(), center->points[0], query);
  if (!map.ok()) return map.status();
  if (!obj && flags.png.empty()) {
    std::string out;
    for (size_t i = 0; i < map->vertices.size(); ++i) {
      out += absl::StrFormat("%d %.17g %.17g\n", map->vertices[i], map->u[i], map->v[i]);
    }
    return WriteFileOrStdout(flags.out, out);
  }
  // The mesh of the version that answered the map.
  const int64_t version = map->version != 0 ? map->version : flags.model.version;
  absl::StatusOr<Mesh> mesh = client->GetMesh(ModelRef(flags.model.name, version));
  if (!mesh.ok()) return mesh.status();
  if (version != 0 && mesh->version != version) {
    return absl::DataLossError(absl::StrFormat(
        "the server sent the mesh of version %d for the exponential map of version %d",
        mesh->version, version));
  }
  if (obj) {
    const std::string stem = flags.out.substr(0, flags.out.size() - 4);
    const std::string texture =
        flags.image.empty() ? BaseName(stem) + "_checker.png" : BaseName(flags.image);
    absl::StatusOr<DecalFiles> files =
        DecalToObj(*mesh, *map, query.radius, BaseName(stem) + ".mtl", texture);
    if (!files.ok()) return files.status();
    const std::string dir = flags.out.substr(0, flags.out.size() - BaseName(flags.out).size());
    if (absl::Status s = WriteFileOrStdout(flags.out, files->obj); !s.ok()) return s;
    if (absl::Status s = WriteFileOrStdout(stem + ".mtl", files->mtl); !s.ok()) return s;
    const std::string texture_path = dir + texture;
    if (texture_path == flags.png) {
      return InputError(absl::InvalidArgumentError(
          absl::StrCat("--png ", flags.png, " would overwrite the decal's texture")));
    }
    if (flags.image.empty()) {
      if (absl::Status s = WriteFileOrStdout(texture_path, EncodePng(Checkerboard(1024, 8)));
          !s.ok()) {
        return s;
      }
    } else if (texture_path != flags.image) {
      if (absl::Status s = WriteFileOrStdout(texture_path, image); !s.ok()) return s;
    }
  }
  if (!flags.png.empty()) {
    absl::StatusOr<Image> picture = RenderDecal(*mesh, *map, query.radius, RenderOptions{});
    if (!picture.ok()) return picture.status();
    if (absl::Status s = WriteFileOrStdout(flags.png, EncodePng(*picture)); !s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace

void AddExpMapCommand(CLI::App* app, absl::Status* status) {
  auto flags = std::make_shared<ExpMapFlags>();
  CLI::App* expmap = app->add_subcommand(
      "expmap",
      "The exponential map (geodesic polar coordinates) round a point: a textured decal "
      "(--out X.obj), lines 'vertex u v', and a rendered picture (--png)");
  AddConnectionFlags(expmap, &flags->conn);
  AddModelFlags(expmap, &flags->model);
  expmap->add_option("--center", flags->center, "The centre: \"F W0 W1 W2\"")->required();
  expmap->add_option("--radius", flags->query.radius, "Geodesic radius of the map")->required();
  expmap
      ->add_option("--direction", flags->direction,
                   "Reference direction X Y Z (theta = 0), projected into the centre's face; "
                   "default the face's first edge")
      ->expected(3);
  AddNearPairsFlags(expmap, &flags->query.near_pairs);
  expmap->add_option("--tolerance", flags->query.tolerance,
                     "Relative error tolerance of the distances r (as for distance)");
  expmap
      ->add_option("-o,--out", flags->out,
                   "Output: X.obj writes the decal (X.obj, X.mtl and the texture X_checker.png); "
                   "anything else gets lines 'vertex u v' ('-': standard output)")
      ->capture_default_str();
  expmap->add_option("--image", flags->image,
                     "With --out X.obj: the picture to apply instead of a checkerboard (copied "
                     "beside X.obj)");
  expmap->add_option("--png", flags->png,
                     "Also render the decal on the whole mesh to this PNG (800x800)");
  expmap->callback([flags, status] { *status = ExpMapCommand(*flags); });
}

[[maybe_unused]] const bool kRegistered = RegisterVerb(60, AddExpMapCommand);

}  // namespace geodex::client::cli
