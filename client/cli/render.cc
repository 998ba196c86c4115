#include "client/cli/render.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "client/cli/decal.h"

namespace geodex::client::cli {
namespace {

using Vec3 = std::array<double, 3>;

// Light that reaches faces seen edge-on, so their shape stays readable.
constexpr double kAmbient = 0.3;
// The ring's width as a fraction of the radius.
constexpr double kRingWidth = 0.01;
// The default view frames a region this many radii wide.
constexpr double kFramedRadii = 3;
// How many of the nearest mapped vertices estimate the map's centre.
constexpr size_t kCentreFitVertices = 16;
// The near clipping plane, as a fraction of the eye's distance to the target:
// small enough to keep nearby geometry, large enough for a usable 1/z.
constexpr double kNearFraction = 1e-4;
constexpr int kMaxImageSide = 16384;
constexpr int kMaxCheckerSquares = 4096;

Vec3 Add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec3 Scale(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double Norm(const Vec3& a) { return std::sqrt(Dot(a, a)); }
bool IsFinite(const Vec3& a) {
  return std::isfinite(a[0]) && std::isfinite(a[1]) && std::isfinite(a[2]);
}

Vec3 FaceCross(const Mesh& mesh, const std::array<uint32_t, 3>& face) {
  const Vec3& p0 = mesh.positions[face[0]];
  return Cross(Sub(mesh.positions[face[1]], p0), Sub(mesh.positions[face[2]], p0));
}

// Where (u, v) = (0, 0) lies in space, and the tangent plane's normal
// e_u x e_v, from an affine fit p ~ centre + A (u, v) to the nearest mapped
// vertices. The centre is in general inside a face, so the nearest vertex
// alone is off by up to an edge length; weights 1 / r^2 keep the fit local
// where the surface is curved.
struct CentreEstimate {
  Vec3 centre;
  Vec3 tangent_normal = {0, 0, 0};  // zero when the fit is degenerate
};

CentreEstimate EstimateMapCentre(const Mesh& mesh, const ExpMap& map, double radius) {
  std::vector<size_t> order(map.vertices.size());
  std::iota(order.begin(), order.end(), size_t{0});
  const size_t k = std::min(kCentreFitVertices, order.size());
  // Entries are distinct vertices, so (r, index) orders them totally and the
  // choice does not depend on the sort's tie handling.
  std::partial_sort(order.begin(), order.begin() + k, order.end(), [&](size_t a, size_t b) {
    return map.r[a] != map.r[b] ? map.r[a] < map.r[b] : a < b;
  });
  const size_t nearest = order[0];
  CentreEstimate estimate{mesh.positions[map.vertices[nearest]]};
  if (k < 3) return estimate;

  const double softening = 1e-3 * radius;
  double weight_sum = 0, mean_u = 0, mean_v = 0;
  Vec3 mean_p = {0, 0, 0};
  std::vector<double> weights(k);
  for (size_t i = 0; i < k; ++i) {
    const size_t e = order[i];
    weights[i] = 1 / (map.r[e] * map.r[e] + softening * softening);
    weight_sum += weights[i];
    mean_u += weights[i] * map.u[e];
    mean_v += weights[i] * map.v[e];
    mean_p = Add(mean_p, Scale(mesh.positions[map.vertices[e]], weights[i]));
  }
  mean_u /= weight_sum;
  mean_v /= weight_sum;
  mean_p = Scale(mean_p, 1 / weight_sum);
  double c_uu = 0, c_uv = 0, c_vv = 0;
  Vec3 c_pu = {0, 0, 0}, c_pv = {0, 0, 0};
  for (size_t i = 0; i < k; ++i) {
    const size_t e = order[i];
    const double du = map.u[e] - mean_u, dv = map.v[e] - mean_v;
    const Vec3 dp = Sub(mesh.positions[map.vertices[e]], mean_p);
    c_uu += weights[i] * du * du;
    c_uv += weights[i] * du * dv;
    c_vv += weights[i] * dv * dv;
    c_pu = Add(c_pu, Scale(dp, weights[i] * du));
    c_pv = Add(c_pv, Scale(dp, weights[i] * dv));
  }
  const double det = c_uu * c_vv - c_uv * c_uv;
  const double trace = c_uu + c_vv;
  if (!(det > 1e-12 * trace * trace)) return estimate;  // collinear (u, v): no plane
  // A = C_pq C_qq^-1, column by column.
  const Vec3 e_u = Scale(Sub(Scale(c_pu, c_vv), Scale(c_pv, c_uv)), 1 / det);
  const Vec3 e_v = Scale(Sub(Scale(c_pv, c_uu), Scale(c_pu, c_uv)), 1 / det);
  const Vec3 centre = Sub(mean_p, Add(Scale(e_u, mean_u), Scale(e_v, mean_v)));
  // The centre is within r of every mapped vertex; a fit far from the
  // nearest one has been thrown off by a strongly folded surface.
  const double slack = 2 * map.r[nearest] + 1e-9 * radius;
  if (!IsFinite(centre) || Norm(Sub(centre, estimate.centre)) > slack) return estimate;
  estimate.centre = centre;
  estimate.tangent_normal = Cross(e_u, e_v);
  return estimate;
}

absl::Status CheckFieldOfView(double degrees) {
  if (std::isfinite(degrees) && degrees > 0 && degrees < 180) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrFormat("the field of view must be between 0 and 180 degrees, not %g", degrees));
}

Camera CameraForPatch(const Mesh& mesh, const ExpMap& map, const DecalPatch& patch, double radius,
                      double field_of_view_degrees) {
  const CentreEstimate estimate = EstimateMapCentre(mesh, map, radius);
  // Area-weighted: the sum of the faces' cross products.
  Vec3 normal = {0, 0, 0};
  double total_area = 0;
  for (const int32_t f : patch.faces) {
    const Vec3 cross = FaceCross(mesh, mesh.faces[f]);
    normal = Add(normal, cross);
    total_area += Norm(cross);
  }
  // A decal wrapped round most of a closed surface has normals that cancel;
  // the tangent plane at the centre is then the better guide.
  if (!(Norm(normal) > 1e-6 * total_area)) normal = estimate.tangent_normal;
  if (!(Norm(normal) > 0) || !IsFinite(normal)) normal = {0, 0, 1};
  normal = Scale(normal, 1 / Norm(normal));

  const double half_angle = field_of_view_degrees * std::numbers::pi / 360;
  const double distance = kFramedRadii / 2 * radius / std::tan(half_angle);
  Camera camera;
  camera.target = estimate.centre;
  camera.eye = Add(estimate.centre, Scale(normal, distance));
  // At most one axis is within acos(0.9) of any direction, so one of the
  // first two always qualifies.
  for (const Vec3& axis : {Vec3{0, 1, 0}, Vec3{0, 0, 1}, Vec3{1, 0, 0}}) {
    if (std::abs(Dot(axis, normal)) < 0.9) {
      camera.up = axis;
      break;
    }
  }
  return camera;
}

// The camera's orthonormal frame and pinhole projection.
struct View {
  Vec3 eye, right, up, forward;
  double focal = 0;  // pixels per unit of x / z
  double centre_x = 0, centre_y = 0;
  double near = 0;
};

absl::StatusOr<View> MakeView(const Camera& camera, const RenderOptions& options) {
  if (!IsFinite(camera.eye) || !IsFinite(camera.target) || !IsFinite(camera.up)) {
    return absl::InvalidArgumentError("the camera's eye, target and up must be finite");
  }
  const Vec3 ahead = Sub(camera.target, camera.eye);
  const double distance = Norm(ahead);
  if (!(distance > 0)) return absl::InvalidArgumentError("the camera's eye is at its target");
  View view;
  view.eye = camera.eye;
  view.forward = Scale(ahead, 1 / distance);
  const Vec3 right = Cross(view.forward, camera.up);
  const double up_norm = Norm(camera.up);
  if (!(Norm(right) > 1e-9 * up_norm)) {
    return absl::InvalidArgumentError("the camera's up vector is zero or along the view direction");
  }
  view.right = Scale(right, 1 / Norm(right));
  view.up = Cross(view.right, view.forward);
  const double half_side = std::min(options.width, options.height) / 2.0;
  view.focal = half_side / std::tan(options.field_of_view_degrees * std::numbers::pi / 360);
  view.centre_x = options.width / 2.0;
  view.centre_y = options.height / 2.0;
  view.near = kNearFraction * distance;
  return view;
}

// A triangle corner in camera coordinates (x right, y up, z the depth along
// the view direction) with the map coordinates it carries.
struct ViewVertex {
  Vec3 position;
  double u = 0, v = 0;
};

ViewVertex Lerp(const ViewVertex& a, const ViewVertex& b, double t) {
  return {Add(a.position, Scale(Sub(b.position, a.position), t)), a.u + t * (b.u - a.u),
          a.v + t * (b.v - a.v)};
}

// The part of a triangle in front of the near plane, as a convex polygon of
// up to four corners; returns how many.
int ClipToNearPlane(const std::array<ViewVertex, 3>& triangle, double near,
                    std::array<ViewVertex, 4>* polygon) {
  int count = 0;
  for (int i = 0; i < 3; ++i) {
    const ViewVertex& a = triangle[i];
    const ViewVertex& b = triangle[(i + 1) % 3];
    const bool a_in = a.position[2] >= near, b_in = b.position[2] >= near;
    if (a_in) (*polygon)[count++] = a;
    if (a_in != b_in) {
      const double t = (near - a.position[2]) / (b.position[2] - a.position[2]);
      (*polygon)[count++] = Lerp(a, b, t);
    }
  }
  return count;
}

// What a face looks like: kMeshColor, or the decal's checkerboard.
struct FacePaint {
  bool textured = false;
  double light = 1;  // the shading factor, kAmbient..1
};

struct DecalPaint {
  double radius = 1;
  int checker_squares = 8;
  bool draw_radius_ring = true;
};

Rgb Shade(const Rgb& color, double light) {
  Rgb out;
  for (int c = 0; c < 3; ++c) {
    out[c] = static_cast<uint8_t>(std::clamp(std::lround(color[c] * light), 0L, 255L));
  }
  return out;
}

struct FrameBuffer {
  Image image;
  std::vector<double> inverse_depth;  // 0: nothing drawn (infinitely far)
};

// A corner projected to the screen, with what is interpolated linearly there:
// 1/z and the map coordinates over z (perspective-correct interpolation).
struct ScreenVertex {
  double x = 0, y = 0;
  double inverse_depth = 0, u_over_depth = 0, v_over_depth = 0;
};

double EdgeFunction(const ScreenVertex& a, const ScreenVertex& b, double x, double y) {
  return (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x);
}

void RasterizeTriangle(const std::array<ScreenVertex, 3>& s, const FacePaint& paint,
                       const DecalPaint& decal, FrameBuffer* buffer) {
  const double area = EdgeFunction(s[0], s[1], s[2].x, s[2].y);
  if (!(std::abs(area) > 0)) return;  // seen edge-on, or not finite
  const int width = buffer->image.width, height = buffer->image.height;
  // Pixel (x, y) is sampled at its centre (x + 0.5, y + 0.5). Bounds are
  // clamped as doubles: a corner near the near plane projects far off-screen.
  const auto first_pixel = [](double lo, int size) {
    return static_cast<int>(std::clamp(std::ceil(lo - 0.5), 0.0, static_cast<double>(size)));
  };
  const auto last_pixel = [](double hi, int size) {
    return static_cast<int>(std::clamp(std::floor(hi - 0.5), -1.0, size - 1.0));
  };
  const int x0 = first_pixel(std::min({s[0].x, s[1].x, s[2].x}), width);
  const int x1 = last_pixel(std::max({s[0].x, s[1].x, s[2].x}), width);
  const int y0 = first_pixel(std::min({s[0].y, s[1].y, s[2].y}), height);
  const int y1 = last_pixel(std::max({s[0].y, s[1].y, s[2].y}), height);
  const Rgb flat = Shade(kMeshColor, paint.light);
  for (int y = y0; y <= y1; ++y) {
    const double py = y + 0.5;
    for (int x = x0; x <= x1; ++x) {
      const double px = x + 0.5;
      const double w0 = EdgeFunction(s[1], s[2], px, py) / area;
      const double w1 = EdgeFunction(s[2], s[0], px, py) / area;
      const double w2 = EdgeFunction(s[0], s[1], px, py) / area;
      if (w0 < 0 || w1 < 0 || w2 < 0) continue;
      const double inverse_depth =
          w0 * s[0].inverse_depth + w1 * s[1].inverse_depth + w2 * s[2].inverse_depth;
      const size_t pixel = static_cast<size_t>(y) * width + x;
      // Strictly nearer: where faces meet, the one drawn first keeps the
      // pixel, so the picture depends on the face order only, not on timing.
      if (!(inverse_depth > buffer->inverse_depth[pixel])) continue;
      buffer->inverse_depth[pixel] = inverse_depth;
      Rgb color = flat;
      if (paint.textured) {
        const double u =
            (w0 * s[0].u_over_depth + w1 * s[1].u_over_depth + w2 * s[2].u_over_depth) /
            inverse_depth;
        const double v =
            (w0 * s[0].v_over_depth + w1 * s[1].v_over_depth + w2 * s[2].v_over_depth) /
            inverse_depth;
        const bool on_ring =
            decal.draw_radius_ring && std::hypot(u, v) >= (1 - kRingWidth) * decal.radius;
        const auto [tex_s, tex_t] = DecalTextureCoordinates(u, v, decal.radius);
        color = Shade(on_ring ? kRingColor : CheckerboardColor(tex_s, tex_t, decal.checker_squares),
                      paint.light);
      }
      std::copy(color.begin(), color.end(), buffer->image.rgb.begin() + 3 * pixel);
    }
  }
}

void DrawFace(const std::array<ViewVertex, 3>& corners, const FacePaint& paint,
              const DecalPaint& decal, const View& view, FrameBuffer* buffer) {
  std::array<ViewVertex, 4> polygon;
  const int count = ClipToNearPlane(corners, view.near, &polygon);
  std::array<ScreenVertex, 4> screen;
  for (int i = 0; i < count; ++i) {
    const ViewVertex& c = polygon[i];
    const double inverse_depth = 1 / c.position[2];
    screen[i] = {view.centre_x + view.focal * c.position[0] * inverse_depth,
                 view.centre_y - view.focal * c.position[1] * inverse_depth, inverse_depth,
                 c.u * inverse_depth, c.v * inverse_depth};
  }
  for (int i = 1; i + 1 < count; ++i) {
    RasterizeTriangle({screen[0], screen[i], screen[i + 1]}, paint, decal, buffer);
  }
}

absl::Status CheckOptions(const RenderOptions& options) {
  if (options.width < 1 || options.width > kMaxImageSide || options.height < 1 ||
      options.height > kMaxImageSide) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the picture must be 1..%d pixels on each side, not %d x %d", kMaxImageSide,
                        options.width, options.height));
  }
  if (options.checker_squares < 1 || options.checker_squares > kMaxCheckerSquares) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the number of checker squares must be 1..%d, not %d", kMaxCheckerSquares,
                        options.checker_squares));
  }
  return CheckFieldOfView(options.field_of_view_degrees);
}

}  // namespace

absl::StatusOr<Camera> DefaultDecalCamera(const Mesh& mesh, const ExpMap& map, double radius,
                                          double field_of_view_degrees) {
  if (absl::Status s = CheckDecalRadius(radius); !s.ok()) return s;
  if (absl::Status s = CheckFieldOfView(field_of_view_degrees); !s.ok()) return s;
  absl::StatusOr<DecalPatch> patch = FindDecalPatch(mesh, map);
  if (!patch.ok()) return patch.status();
  return CameraForPatch(mesh, map, *patch, radius, field_of_view_degrees);
}

absl::StatusOr<Image> RenderDecal(const Mesh& mesh, const ExpMap& map, double radius,
                                  const RenderOptions& options) {
  if (absl::Status s = CheckDecalRadius(radius); !s.ok()) return s;
  if (absl::Status s = CheckOptions(options); !s.ok()) return s;
  absl::StatusOr<DecalPatch> patch = FindDecalPatch(mesh, map);
  if (!patch.ok()) return patch.status();
  // FindDecalPatch checked the decal's positions; the rest of the mesh is
  // drawn too.
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (const uint32_t vertex : mesh.faces[f]) {
      if (!IsFinite(mesh.positions[vertex])) {
        return absl::InvalidArgumentError(
            absl::StrFormat("mesh vertex %d (of face %d) is at a non-finite position", vertex, f));
      }
    }
  }
  const Camera camera = options.camera.has_value() ? *options.camera
                                                   : CameraForPatch(mesh, map, *patch, radius,
                                                                    options.field_of_view_degrees);
  absl::StatusOr<View> view = MakeView(camera, options);
  if (!view.ok()) return view.status();

  const size_t num_pixels = static_cast<size_t>(options.width) * options.height;
  FrameBuffer buffer{Image{options.width, options.height, std::vector<uint8_t>(3 * num_pixels)},
                     std::vector<double>(num_pixels, 0.0)};
  for (size_t pixel = 0; pixel < num_pixels; ++pixel) {
    std::copy(kBackgroundColor.begin(), kBackgroundColor.end(),
              buffer.image.rgb.begin() + 3 * pixel);
  }
  std::vector<bool> in_decal(mesh.faces.size(), false);
  for (const int32_t f : patch->faces) in_decal[f] = true;
  const DecalPaint decal{radius, options.checker_squares, options.draw_radius_ring};

  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const std::array<uint32_t, 3>& face = mesh.faces[f];
    std::array<ViewVertex, 3> corners;
    for (int i = 0; i < 3; ++i) {
      const Vec3 relative = Sub(mesh.positions[face[i]], view->eye);
      corners[i].position = {Dot(relative, view->right), Dot(relative, view->up),
                             Dot(relative, view->forward)};
      if (in_decal[f]) {
        const int32_t entry = patch->map_entry[face[i]];
        corners[i].u = map.u[entry];
        corners[i].v = map.v[entry];
      }
    }
    const Vec3 cross = FaceCross(mesh, face);
    const double cross_norm = Norm(cross);
    // Two-sided: a face lit from behind is as bright as from the front.
    const double facing = cross_norm > 0 ? std::abs(Dot(cross, view->forward)) / cross_norm : 0.0;
    FacePaint paint;
    paint.textured = in_decal[f];
    paint.light = kAmbient + (1 - kAmbient) * std::min(facing, 1.0);
    DrawFace(corners, paint, decal, *view, &buffer);
  }
  return std::move(buffer.image);
}

}  // namespace geodex::client::cli
