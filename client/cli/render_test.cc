#include "client/cli/render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "client/cli/decal.h"
#include "client/cli/decal_testing.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client::cli {
namespace {

using decal_testing::FlatGrid;
using decal_testing::PlanarExpMap;

const double kTanHalfFov = std::tan(15 * std::numbers::pi / 180);  // the default 30 degrees

Rgb PixelAt(const Image& image, int x, int y) {
  const size_t at = 3 * (static_cast<size_t>(y) * image.width + x);
  return {image.rgb[at], image.rgb[at + 1], image.rgb[at + 2]};
}

// The pixel showing point p, for a camera looking straight down -z with +y
// up and the default field of view (the pinhole model RenderDecal documents).
Rgb PixelShowing(const Image& image, const Camera& camera, const Position& p) {
  const double focal = std::min(image.width, image.height) / 2.0 / kTanHalfFov;
  const double depth = camera.eye[2] - p[2];
  const double x = image.width / 2.0 + focal * (p[0] - camera.eye[0]) / depth;
  const double y = image.height / 2.0 - focal * (p[1] - camera.eye[1]) / depth;
  return PixelAt(image, static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y)));
}

// The point of the plane z = 0 that pixel (x, y) samples (its centre), for a
// camera as in PixelShowing.
Position PointSampledBy(const Image& image, const Camera& camera, int x, int y) {
  const double focal = std::min(image.width, image.height) / 2.0 / kTanHalfFov;
  const double depth = camera.eye[2];
  return {camera.eye[0] + (x + 0.5 - image.width / 2.0) * depth / focal,
          camera.eye[1] - (y + 0.5 - image.height / 2.0) * depth / focal, 0};
}

// A disc of `radius` round the origin in the plane z = 0: a centre vertex,
// a ring at half the radius and one at the radius, `segments` vertices each,
// faces counter-clockwise seen from +z.
Mesh Disc(double radius, int segments) {
  Mesh mesh;
  mesh.positions.push_back({0, 0, 0});
  for (const double ring : {0.5 * radius, radius}) {
    for (int k = 0; k < segments; ++k) {
      const double angle = 2 * std::numbers::pi * k / segments;
      mesh.positions.push_back({ring * std::cos(angle), ring * std::sin(angle), 0});
    }
  }
  const auto inner = [&](int k) { return static_cast<uint32_t>(1 + k % segments); };
  const auto outer = [&](int k) { return static_cast<uint32_t>(1 + segments + k % segments); };
  for (int k = 0; k < segments; ++k) {
    mesh.faces.push_back({0, inner(k), inner(k + 1)});
    mesh.faces.push_back({inner(k), outer(k), outer(k + 1)});
    mesh.faces.push_back({inner(k), outer(k + 1), inner(k + 1)});
  }
  return mesh;
}

// The unit sphere as latitude-longitude quads split in two, with single
// vertices at the poles; faces counter-clockwise seen from outside.
Mesh UvSphere(int latitudes, int longitudes) {
  Mesh mesh;
  mesh.positions.push_back({0, 0, 1});
  for (int i = 1; i < latitudes; ++i) {
    const double polar = std::numbers::pi * i / latitudes;
    for (int j = 0; j < longitudes; ++j) {
      const double azimuth = 2 * std::numbers::pi * j / longitudes;
      mesh.positions.push_back({std::sin(polar) * std::cos(azimuth),
                                std::sin(polar) * std::sin(azimuth), std::cos(polar)});
    }
  }
  mesh.positions.push_back({0, 0, -1});
  const uint32_t south = static_cast<uint32_t>(mesh.positions.size() - 1);
  const auto at = [&](int ring, int j) {
    return static_cast<uint32_t>(1 + (ring - 1) * longitudes + j % longitudes);
  };
  for (int j = 0; j < longitudes; ++j) {
    mesh.faces.push_back({0, at(1, j), at(1, j + 1)});
    for (int i = 1; i + 1 < latitudes; ++i) {
      mesh.faces.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.faces.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
    mesh.faces.push_back({at(latitudes - 1, j), south, at(latitudes - 1, j + 1)});
  }
  return mesh;
}

// Straight above the origin, seeing [-1.5, 1.5]^2 of the plane z = 0.
Camera CameraAbove() { return {{0, 0, 1.5 / kTanHalfFov}, {0, 0, 0}, {0, 1, 0}}; }

RenderOptions SmallPicture(int side = 200) {
  RenderOptions options;
  options.width = options.height = side;
  options.camera = CameraAbove();
  return options;
}

// The colour the decal has at plane point (x, y) for a map centred at the
// origin: flat faces seen head-on keep their colours.
Rgb DecalColorAt(double x, double y, double radius, int squares = 8) {
  const auto [s, t] = DecalTextureCoordinates(x, y, radius);
  return CheckerboardColor(s, t, squares);
}

// A square of two faces at height z over [-half, half]^2, appended to mesh.
void AddSquare(Mesh* mesh, double half, double z, bool faces_first = false) {
  const uint32_t first = static_cast<uint32_t>(mesh->positions.size());
  mesh->positions.push_back({-half, -half, z});
  mesh->positions.push_back({half, -half, z});
  mesh->positions.push_back({half, half, z});
  mesh->positions.push_back({-half, half, z});
  const std::vector<std::array<uint32_t, 3>> faces = {{first, first + 1, first + 2},
                                                      {first, first + 2, first + 3}};
  mesh->faces.insert(faces_first ? mesh->faces.begin() : mesh->faces.end(), faces.begin(),
                     faces.end());
}

TEST(RenderDecal, FlatGridFromAboveShowsTheCheckerboard) {
  const Mesh mesh = FlatGrid(20);  // spacing 0.1
  constexpr double kRadius = 0.8;  // squares of 0.2
  const ExpMap map = PlanarExpMap(mesh, 0, 0, kRadius);
  const RenderOptions options = SmallPicture();
  const absl::StatusOr<Image> image = RenderDecal(mesh, map, kRadius, options);
  ASSERT_TRUE(image.ok()) << image.status();
  ASSERT_EQ(image->width, 200);
  ASSERT_EQ(image->height, 200);
  ASSERT_EQ(image->rgb.size(), 3u * 200 * 200);
  const Camera& camera = *options.camera;

  // The centre of every square well inside the disc, where all faces round
  // the point have their three vertices in the map.
  int checked = 0;
  for (int i = 0; i < 8; ++i) {
    for (int j = 0; j < 8; ++j) {
      const double x = (i + 0.5) * 0.2 - kRadius, y = (j + 0.5) * 0.2 - kRadius;
      if (std::hypot(x, y) > kRadius - 0.15) continue;
      EXPECT_EQ(PixelShowing(*image, camera, {x, y, 0}), DecalColorAt(x, y, kRadius))
          << "square " << i << " " << j;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 32);
  // Orientation: +u is +x and +v is +y, not mirrored: the red quadrant is at
  // the top right, its green row just above the +x axis.
  const Rgb red = PixelShowing(*image, camera, {0.3, 0.3, 0});
  EXPECT_GT(red[0], red[1] + 50);
  const Rgb green = PixelShowing(*image, camera, {0.3, 0.1, 0});
  EXPECT_GT(green[1], green[0] + 40);
  const Rgb below_axis = PixelShowing(*image, camera, {0.3, -0.1, 0});
  EXPECT_LT(std::abs(below_axis[0] - below_axis[1]), 20);

  // The mesh outside the decal, and the background beyond the mesh.
  EXPECT_EQ(PixelShowing(*image, camera, {0.9, -0.9, 0}), kMeshColor);
  EXPECT_EQ(PixelShowing(*image, camera, {-0.95, 0.5, 0}), kMeshColor);
  EXPECT_EQ(PixelShowing(*image, camera, {1.3, 1.3, 0}), kBackgroundColor);
  EXPECT_EQ(PixelShowing(*image, camera, {-1.4, 0.2, 0}), kBackgroundColor);
  EXPECT_EQ(PixelAt(*image, 0, 0), kBackgroundColor);
  EXPECT_EQ(PixelAt(*image, 199, 199), kBackgroundColor);
}

TEST(RenderDecal, ZBufferNearerFacesOccludeWhateverTheFaceOrder) {
  constexpr double kRadius = 0.8;
  const Mesh grid = FlatGrid(20);
  const ExpMap map = PlanarExpMap(grid, 0, 0, kRadius);
  const RenderOptions options = SmallPicture();
  const Camera& camera = *options.camera;

  Mesh occluded = grid;
  AddSquare(&occluded, 0.2, 0.5);
  const absl::StatusOr<Image> image = RenderDecal(occluded, map, kRadius, options);
  ASSERT_TRUE(image.ok()) << image.status();
  // The square in front hides the decal round the centre, not farther out.
  EXPECT_EQ(PixelShowing(*image, camera, {0.1, 0.1, 0}), kMeshColor);
  EXPECT_EQ(PixelShowing(*image, camera, {-0.1, 0.1, 0}), kMeshColor);
  EXPECT_EQ(PixelShowing(*image, camera, {0.5, -0.3, 0}), DecalColorAt(0.5, -0.3, kRadius));

  // Drawn before the decal instead of after: the same picture.
  Mesh occluder_first = grid;
  AddSquare(&occluder_first, 0.2, 0.5, /*faces_first=*/true);
  const absl::StatusOr<Image> first = RenderDecal(occluder_first, map, kRadius, options);
  ASSERT_TRUE(first.ok()) << first.status();
  EXPECT_EQ(first->rgb, image->rgb);

  // A square behind the plane, either order, leaves the picture unchanged.
  const absl::StatusOr<Image> plain = RenderDecal(grid, map, kRadius, options);
  ASSERT_TRUE(plain.ok()) << plain.status();
  for (const bool faces_first : {false, true}) {
    Mesh behind = grid;
    AddSquare(&behind, 0.2, -0.5, faces_first);
    const absl::StatusOr<Image> hidden = RenderDecal(behind, map, kRadius, options);
    ASSERT_TRUE(hidden.ok()) << hidden.status();
    EXPECT_EQ(hidden->rgb, plain->rgb) << faces_first;
  }
}

TEST(RenderDecal, DefaultCameraLooksAtTheCentreAlongTheNormal) {
  constexpr double kRadius = 0.5;
  const double distance = 1.5 * kRadius / kTanHalfFov;
  // A centre inside a face, not at a vertex.
  const Mesh mesh = FlatGrid(20);
  const ExpMap map = PlanarExpMap(mesh, 0.05, -0.03, kRadius);
  absl::StatusOr<Camera> camera = DefaultDecalCamera(mesh, map, kRadius);
  ASSERT_TRUE(camera.ok()) << camera.status();
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(camera->target[c], (Position{0.05, -0.03, 0})[c], 1e-9) << c;
    EXPECT_NEAR(camera->eye[c], (Position{0.05, -0.03, distance})[c], 1e-9) << c;
  }
  EXPECT_EQ(camera->up, (Position{0, 1, 0}));

  // Faces the other way round: seen from below.
  Mesh flipped = mesh;
  for (auto& face : flipped.faces) std::swap(face[1], face[2]);
  camera = DefaultDecalCamera(flipped, map, kRadius);
  ASSERT_TRUE(camera.ok()) << camera.status();
  EXPECT_NEAR(camera->eye[2], -distance, 1e-9);

  // The plane y = 0, normal -y: up cannot be +y, so it is +z.
  Mesh upright = mesh;
  for (Position& p : upright.positions) p = {p[0], 0, p[1]};
  camera = DefaultDecalCamera(upright, map, kRadius);
  ASSERT_TRUE(camera.ok()) << camera.status();
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(camera->target[c], (Position{0.05, 0, -0.03})[c], 1e-9) << c;
    EXPECT_NEAR(camera->eye[c], (Position{0.05, -distance, -0.03})[c], 1e-9) << c;
  }
  EXPECT_EQ(camera->up, (Position{0, 0, 1}));

  // A wider field of view comes closer.
  camera = DefaultDecalCamera(mesh, map, kRadius, 60);
  ASSERT_TRUE(camera.ok()) << camera.status();
  EXPECT_NEAR(camera->eye[2], 1.5 * kRadius / std::tan(std::numbers::pi / 6), 1e-9);
}

TEST(RenderDecal, DefaultCameraFramesTheDecal) {
  constexpr double kRadius = 0.8;
  const Mesh mesh = FlatGrid(20);
  const ExpMap map = PlanarExpMap(mesh, 0, 0, kRadius);
  RenderOptions options;
  options.width = 240;
  options.height = 200;
  const absl::StatusOr<Image> image = RenderDecal(mesh, map, kRadius, options);
  ASSERT_TRUE(image.ok()) << image.status();
  ASSERT_EQ(image->width, 240);
  ASSERT_EQ(image->height, 200);
  const absl::StatusOr<Camera> camera = DefaultDecalCamera(mesh, map, kRadius);
  ASSERT_TRUE(camera.ok()) << camera.status();
  for (const auto& [x, y] : {std::pair{0.1, 0.1}, {0.3, 0.5}, {-0.5, -0.3}, {0.5, -0.1}}) {
    EXPECT_EQ(PixelShowing(*image, *camera, {x, y, 0}), DecalColorAt(x, y, kRadius))
        << x << " " << y;
  }
  // Three radii across the smaller side: the grid's edge x = 1 (1.25 radii
  // out) is in the picture, its corners beyond it.
  EXPECT_EQ(PixelShowing(*image, *camera, {0.97, 0, 0}), kMeshColor);
  EXPECT_EQ(PixelAt(*image, 120, 0), kBackgroundColor);
}

TEST(RenderDecal, RingMarksTheRadius) {
  // A disc whose boundary vertices lie on the circle of the radius, so that
  // decal faces reach it all round: the ring is the band of texture
  // coordinates within kRingWidth (1 %) of the radius.
  constexpr double kRadius = 0.8;
  constexpr int kSegments = 64;
  const Mesh mesh = Disc(kRadius, kSegments);
  const ExpMap map = PlanarExpMap(mesh, 0, 0, kRadius * (1 + 1e-12));
  RenderOptions options = SmallPicture(400);
  options.draw_radius_ring = true;
  const absl::StatusOr<Image> with_ring = RenderDecal(mesh, map, kRadius, options);
  ASSERT_TRUE(with_ring.ok()) << with_ring.status();
  // The boundary's chords come within cos(pi / segments) of the radius.
  const double inner_chord = kRadius * std::cos(std::numbers::pi / kSegments);
  int ring_pixels = 0;
  for (int y = 0; y < 400; ++y) {
    for (int x = 0; x < 400; ++x) {
      const Position p = PointSampledBy(*with_ring, *options.camera, x, y);
      const double r = std::hypot(p[0], p[1]);
      const bool ring = PixelAt(*with_ring, x, y) == kRingColor;
      ring_pixels += ring;
      if (r < 0.989 * kRadius || r > kRadius) {
        ASSERT_FALSE(ring) << x << " " << y << " r " << r;
      } else if (r > 0.991 * kRadius && r < inner_chord - 1e-3) {
        ASSERT_TRUE(ring) << x << " " << y << " r " << r;
      }
    }
  }
  EXPECT_GT(ring_pixels, 100);

  options.draw_radius_ring = false;
  const absl::StatusOr<Image> without = RenderDecal(mesh, map, kRadius, options);
  ASSERT_TRUE(without.ok()) << without.status();
  for (int y = 0; y < 400; ++y) {
    for (int x = 0; x < 400; ++x) ASSERT_NE(PixelAt(*without, x, y), kRingColor) << x << " " << y;
  }
}

TEST(RenderDecal, DefaultCameraOnASphereCap) {
  // The unit sphere round its north pole: r = the polar angle, theta the
  // azimuth, counter-clockwise about the outward normal.
  const Mesh sphere = UvSphere(24, 48);
  constexpr double kRadius = 0.6;
  ExpMap map;
  for (size_t vertex = 0; vertex < sphere.positions.size(); ++vertex) {
    const Position& p = sphere.positions[vertex];
    const double r = std::acos(std::clamp(p[2], -1.0, 1.0));
    if (r > kRadius) continue;
    const double theta = r > 0 ? std::atan2(p[1], p[0]) : 0.0;
    map.vertices.push_back(static_cast<int32_t>(vertex));
    map.r.push_back(r);
    map.theta.push_back(theta);
    map.u.push_back(r * std::cos(theta));
    map.v.push_back(r * std::sin(theta));
  }
  const absl::StatusOr<Camera> camera = DefaultDecalCamera(sphere, map, kRadius);
  ASSERT_TRUE(camera.ok()) << camera.status();
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(camera->target[c], (Position{0, 0, 1})[c], 1e-9) << c;
    EXPECT_NEAR(camera->eye[c], (Position{0, 0, 1 + 1.5 * kRadius / kTanHalfFov})[c], 1e-9) << c;
  }
  EXPECT_EQ(camera->up, (Position{0, 1, 0}));
  // From above, the pole's neighbourhood looks like the flat decal: the red
  // quadrant to the top right.
  RenderOptions options;
  options.width = options.height = 200;
  const absl::StatusOr<Image> framed = RenderDecal(sphere, map, kRadius, options);
  ASSERT_TRUE(framed.ok()) << framed.status();
  const Rgb red = PixelShowing(*framed, *camera, {0.2, 0.2, std::sqrt(1 - 0.08)});
  EXPECT_GT(red[0], red[1] + 40);
}

TEST(RenderDecal, SameInputSamePicture) {
  const Mesh mesh = FlatGrid(30);
  const ExpMap map = PlanarExpMap(mesh, 0.11, 0.07, 0.6);
  const absl::StatusOr<Image> a = RenderDecal(mesh, map, 0.6);
  const absl::StatusOr<Image> b = RenderDecal(mesh, map, 0.6);
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_TRUE(b.ok()) << b.status();
  EXPECT_EQ(a->width, 800);
  EXPECT_EQ(a->height, 800);
  EXPECT_EQ(a->rgb, b->rgb);
}

TEST(RenderDecal, NearPlaneClipsWhatIsBehindTheCamera) {
  // Standing on the plane, looking along +y: half of it is behind the eye.
  const Mesh mesh = FlatGrid(20);
  const ExpMap map = PlanarExpMap(mesh, 0, 0, 0.8);
  RenderOptions options;
  options.width = options.height = 100;
  options.camera = Camera{{0, 0, 0.05}, {0, 1, 0.05}, {0, 0, 1}};
  const absl::StatusOr<Image> image = RenderDecal(mesh, map, 0.8, options);
  ASSERT_TRUE(image.ok()) << image.status();
  for (int x = 0; x < 100; ++x) {
    for (int y = 0; y < 45; ++y) {
      ASSERT_EQ(PixelAt(*image, x, y), kBackgroundColor) << x << " " << y;  // the sky
    }
    EXPECT_NE(PixelAt(*image, x, 99), kBackgroundColor) << x;  // the floor
  }
}

TEST(RenderDecal, BadInputIsAnError) {
  const Mesh mesh = FlatGrid(10);
  const ExpMap good = PlanarExpMap(mesh, 0, 0, 0.5);
  RenderOptions small;
  small.width = small.height = 32;
  const auto code = [&](const Mesh& m, const ExpMap& map, double radius,
                        const RenderOptions& options) {
    return RenderDecal(m, map, radius, options).status().code();
  };
  ASSERT_EQ(code(mesh, good, 0.5, small), absl::StatusCode::kOk);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(code(mesh, ExpMap{}, 0.5, small), absl::StatusCode::kInvalidArgument) << "empty";
  EXPECT_EQ(DefaultDecalCamera(mesh, ExpMap{}, 0.5).status().code(),
            absl::StatusCode::kInvalidArgument);
  ExpMap map = good;
  map.u[3] = nan;
  EXPECT_EQ(code(mesh, map, 0.5, small), absl::StatusCode::kInvalidArgument) << "NaN u";
  map = good;
  map.vertices.back() = 1000;
  EXPECT_EQ(code(mesh, map, 0.5, small), absl::StatusCode::kOutOfRange) << "vertex id";
  Mesh far_nan = mesh;
  far_nan.positions[0] = {nan, 0, 0};  // a corner, outside the decal
  EXPECT_EQ(code(far_nan, good, 0.5, small), absl::StatusCode::kInvalidArgument) << "NaN position";
  for (const double radius : {0.0, -0.5, nan}) {
    EXPECT_EQ(code(mesh, good, radius, small), absl::StatusCode::kInvalidArgument) << radius;
  }

  RenderOptions options = small;
  options.width = 0;
  EXPECT_EQ(code(mesh, good, 0.5, options), absl::StatusCode::kInvalidArgument) << "width";
  options = small;
  options.height = 20000;
  EXPECT_EQ(code(mesh, good, 0.5, options), absl::StatusCode::kInvalidArgument) << "height";
  options = small;
  options.checker_squares = 0;
  EXPECT_EQ(code(mesh, good, 0.5, options), absl::StatusCode::kInvalidArgument) << "squares";
  for (const double fov : {0.0, 180.0, nan}) {
    options = small;
    options.field_of_view_degrees = fov;
    EXPECT_EQ(code(mesh, good, 0.5, options), absl::StatusCode::kInvalidArgument) << fov;
  }
  options = small;
  options.camera = Camera{{0, 0, 1}, {0, 0, 1}, {0, 1, 0}};
  EXPECT_EQ(code(mesh, good, 0.5, options), absl::StatusCode::kInvalidArgument) << "eye = target";
  options.camera = Camera{{0, 0, 1}, {0, 0, 0}, {0, 0, 5}};
  EXPECT_EQ(code(mesh, good, 0.5, options), absl::StatusCode::kInvalidArgument) << "up along view";
  options.camera = Camera{{0, 0, 1}, {0, 0, 0}, {0, 0, 0}};
  EXPECT_EQ(code(mesh, good, 0.5, options), absl::StatusCode::kInvalidArgument) << "zero up";
  options.camera = Camera{{0, 0, nan}, {0, 0, 0}, {0, 1, 0}};
  EXPECT_EQ(code(mesh, good, 0.5, options), absl::StatusCode::kInvalidArgument) << "NaN eye";
}

}  // namespace
}  // namespace geodex::client::cli
