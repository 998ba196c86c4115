// geodex._core.Index: an index file answering queries in the mesh file's ids,
// through query::InputQueries, the same layer the server answers with, so
// that the in-process answers equal the server's to the bit (the server's
// Distance and StreamDistances are DistanceBatch, its Matrix one
// DistanceBatch per row, as here).
//
// The Python layer (geodex/_inprocess.py) validates shapes and finiteness
// and passes C-contiguous int32 / float64 arrays; this layer validates the
// points against the index (InputQueries::Read: face ids in range, weights
// summing to 1) with the server's messages ("a[17]: ..."), and computes with
// the GIL released, large batches split over threads (each with its own
// QueryScratch; the answers do not depend on the split).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "core/index/index_report.h"
#include "core/python/bindings.h"
#include "core/python/python_status.h"
#include "core/query/exp_map.h"
#include "core/query/input_queries.h"
#include "core/query/engine/query_types.h"
#include "pybind11/numpy.h"
#include "pybind11/pybind11.h"
#include "pybind11/stl.h"

namespace geodex::python {
namespace {

namespace py = pybind11;

using Faces = py::array_t<int32_t, py::array::c_style | py::array::forcecast>;
using Weights = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Work below this many items a thread stays on one thread.
constexpr int64_t kMinItemsPerThread = 4096;
// Pairs per DistanceBatch call: the translated points of one block at a time
// per thread, not of the whole input.
constexpr int64_t kBlockPairs = 8192;

// Calls fn(begin, end, part) for `parts` consecutive ranges covering [0, n),
// each on its own thread (the first on the caller's).
template <class Fn>
void ForRanges(int64_t n, int parts, Fn fn) {
  std::vector<std::thread> threads;
  const int64_t step = (n + parts - 1) / std::max(parts, 1);
  for (int p = 1; p < parts; ++p) {
    const int64_t begin = std::min(n, p * step), end = std::min(n, (p + 1) * step);
    threads.emplace_back([&fn, begin, end, p] { fn(begin, end, p); });
  }
  fn(0, std::min(n, step), 0);
  for (std::thread& t : threads) t.join();
}

// The first error of `statuses`, in order, or OK.
absl::Status FirstError(const std::vector<absl::Status>& statuses) {
  for (const absl::Status& s : statuses) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

// A point name "name[offset + i]" for a range of a larger array.
query::PointName NamedFrom(const std::string& name, int64_t offset) {
  return [name, offset](size_t i) {
    return absl::StrFormat("%s[%d]", name, offset + static_cast<int64_t>(i));
  };
}

query::NearPairs NearPairsOf(int mode) {
  switch (mode) {
    case 2:
      return query::NearPairs::kUnfold;
    case 3:
      return query::NearPairs::kExact;
    default:  // 0 (the default) and 1
      return query::NearPairs::kPath;
  }
}

query::DistanceOptions DistanceOptionsOf(int near_pairs, double tolerance,
                                         double refine_below = 0) {
  query::DistanceOptions options;
  options.near_pairs = NearPairsOf(near_pairs);
  options.tolerance = tolerance;
  options.refine_below_l1000 = refine_below;
  return options;
}

std::span<const int32_t> SpanOf(const Faces& a) {
  return {a.data(), static_cast<size_t>(a.size())};
}
std::span<const double> SpanOf(const Weights& a) {
  return {a.data(), static_cast<size_t>(a.size())};
}

class Index {
 public:
  Index(const std::string& path, int threads) {
    {
      py::gil_scoped_release release;
      queries_ = ValueOrThrow(query::InputQueries::Open(path));
    }
    threads_ = threads > 0 ? threads : std::max(1u, std::thread::hardware_concurrency());
  }

  int32_t num_vertices() const { return queries_->num_vertices(); }
  int32_t num_faces() const { return queries_->num_faces(); }
  int32_t num_samples() const { return queries_->index().num_samples(); }
  bool has_error_bounds() const { return queries_->has_error_bounds(); }
  std::string report() const { return std::string(queries_->index().report()); }
  // The build report as JSON (core/index/index_report.h), as the server's
  // GetModel sends it.
  std::string report_json() const {
    return index::IndexReportJson(index::MakeIndexReport(queries_->index()));
  }

  // (distances, bounds or None) of pairs (a[i], b[i]).
  py::tuple Distance(const Faces& a_faces, const Weights& a_weights, const Faces& b_faces,
                     const Weights& b_weights, int near_pairs, double tolerance,
                     bool bounds, double refine_below) const {
    const int64_t n = a_faces.size();
    if (b_faces.size() != n) {
      throw StatusError(absl::InvalidArgumentError(
          absl::StrFormat("a has %d points but b has %d; they must pair up", n, b_faces.size())));
    }
    py::array_t<double> out(n);
    std::optional<py::array_t<double>> out_bounds;
    if (bounds) out_bounds.emplace(n);
    double* d = out.mutable_data();
    double* bnd = bounds ? out_bounds->mutable_data() : nullptr;
    const query::DistanceOptions options = DistanceOptionsOf(near_pairs, tolerance, refine_below);
    {
      py::gil_scoped_release release;
      // Blocks of kBlockPairs pairs, each read (checked and translated) and
      // answered in turn; the threads take consecutive runs of blocks.
      const int64_t blocks = (n + kBlockPairs - 1) / kBlockPairs;
      std::vector<absl::Status> a_status(blocks), b_status(blocks), status(blocks);
      const int parts = static_cast<int>(std::min<int64_t>(Parts(n), std::max<int64_t>(blocks, 1)));
      ForRanges(blocks, parts, [&](int64_t first, int64_t last, int) {
        query::QueryScratch scratch;
        query::EnginePoints a, b;
        for (int64_t k = first; k < last; ++k) {
          const int64_t begin = k * kBlockPairs, size = std::min(n - begin, kBlockPairs);
          a_status[k] = queries_->Read(SpanOf(a_faces).subspan(begin, size),
                                       SpanOf(a_weights).subspan(3 * begin, 3 * size),
                                       NamedFrom("a", begin), &a);
          b_status[k] = queries_->Read(SpanOf(b_faces).subspan(begin, size),
                                       SpanOf(b_weights).subspan(3 * begin, 3 * size),
                                       NamedFrom("b", begin), &b);
          if (!a_status[k].ok() || !b_status[k].ok()) continue;
          status[k] = queries_->DistanceBatch(
              a, b, std::span<double>(d + begin, size), options, &scratch,
              bnd ? std::span<double>(bnd + begin, size) : std::span<double>());
        }
      });
      // All of a is checked before any of b, as the server does.
      ThrowIfError(FirstError(a_status));
      ThrowIfError(FirstError(b_status));
      ThrowIfError(FirstError(status));
    }
    return py::make_tuple(out, bounds ? py::object(*out_bounds) : py::object(py::none()));
  }

  // (S x T distances, bounds or None); row s is one DistanceBatch of
  // sources[s] repeated against the targets.
  py::tuple Matrix(const Faces& s_faces, const Weights& s_weights, const Faces& t_faces,
                   const Weights& t_weights, int near_pairs, double tolerance, bool bounds,
                   double refine_below) const {
    const int64_t s = s_faces.size(), t = t_faces.size();
    py::array_t<double> out({s, t});
    std::optional<py::array_t<double>> out_bounds;
    if (bounds) out_bounds.emplace(std::vector<int64_t>{s, t});
    double* m = out.mutable_data();
    double* bnd = bounds ? out_bounds->mutable_data() : nullptr;
    const query::DistanceOptions options = DistanceOptionsOf(near_pairs, tolerance, refine_below);
    {
      py::gil_scoped_release release;
      query::EnginePoints sources, targets;
      ThrowIfError(
          queries_->Read(SpanOf(s_faces), SpanOf(s_weights), query::Named("sources"), &sources));
      ThrowIfError(
          queries_->Read(SpanOf(t_faces), SpanOf(t_weights), query::Named("targets"), &targets));
      const int parts = static_cast<int>(std::min<int64_t>(Parts(s * t), std::max<int64_t>(s, 1)));
      std::vector<absl::Status> status(parts);
      ForRanges(s, parts, [&](int64_t begin, int64_t end, int p) {
        query::QueryScratch scratch;
        query::EnginePoints row;
        for (int64_t r = begin; r < end && status[p].ok(); ++r) {
          row.AssignRepeated(sources, r, t);
          status[p] = queries_->DistanceBatch(
              row, targets, std::span<double>(m + r * t, t), options, &scratch,
              bnd ? std::span<double>(bnd + r * t, t) : std::span<double>());
        }
      });
      ThrowIfError(FirstError(status));
    }
    return py::make_tuple(out, bounds ? py::object(*out_bounds) : py::object(py::none()));
  }

  // [(positions (K, 3), faces (K,), weights (K, 3), length)] per pair; K = 0
  // and length inf between components.
  py::list Path(const Faces& a_faces, const Weights& a_weights, const Faces& b_faces,
                const Weights& b_weights, int exact_corridor) const {
    const int64_t n = a_faces.size();
    if (b_faces.size() != n) {
      throw StatusError(absl::InvalidArgumentError(
          absl::StrFormat("a has %d points but b has %d; they must pair up", n, b_faces.size())));
    }
    std::vector<std::vector<query::PathPoint>> paths(n);
    std::vector<char> reachable(n, 1);
    {
      py::gil_scoped_release release;
      query::EnginePoints a, b;
      ThrowIfError(queries_->Read(SpanOf(a_faces), SpanOf(a_weights), query::Named("a"), &a));
      ThrowIfError(queries_->Read(SpanOf(b_faces), SpanOf(b_weights), query::Named("b"), &b));
      // Paths cost O(k) each: a thread per few pairs is worth it.
      const int parts = static_cast<int>(std::clamp<int64_t>(n / 16, 1, threads_));
      std::vector<absl::Status> status(parts);
      ForRanges(n, parts, [&](int64_t begin, int64_t end, int p) {
        for (int64_t i = begin; i < end && status[p].ok(); ++i) {
          absl::StatusOr<std::vector<query::PathPoint>> path =
              queries_->Path(a, i, b, i, exact_corridor);
          if (path.ok()) {
            paths[i] = *std::move(path);
          } else if (path.status().code() == absl::StatusCode::kNotFound) {
            reachable[i] = 0;  // different components
          } else {
            status[p] = absl::Status(path.status().code(),
                                     absl::StrFormat("pair %d: %s", i, path.status().message()));
          }
        }
      });
      ThrowIfError(FirstError(status));
    }
    py::list out;
    for (int64_t i = 0; i < n; ++i) {
      const std::vector<query::PathPoint>& path = paths[i];
      const int64_t k = static_cast<int64_t>(path.size());
      py::array_t<double> positions({k, int64_t{3}}), weights({k, int64_t{3}});
      py::array_t<int32_t> faces(k);
      double* x = positions.mutable_data();
      double* w = weights.mutable_data();
      int32_t* f = faces.mutable_data();
      const double length =
          reachable[i] ? query::PathLength(path) : std::numeric_limits<double>::infinity();
      for (int64_t j = 0; j < k; ++j) {
        for (int c = 0; c < 3; ++c) {
          x[3 * j + c] = path[j].position[c];
          w[3 * j + c] = path[j].point.w[c];
        }
        f[j] = path[j].point.face;
      }
      out.append(py::make_tuple(positions, faces, weights, length));
    }
    return out;
  }

  // (distances (n,), nearest source (n,)) per vertex of the mesh file.
  py::tuple Field(const Faces& faces, const Weights& weights) const {
    query::DistanceField field;
    {
      py::gil_scoped_release release;
      query::EnginePoints sources;
      ThrowIfError(
          queries_->Read(SpanOf(faces), SpanOf(weights), query::Named("sources"), &sources));
      field = ValueOrThrow(queries_->Field(sources));
    }
    py::array_t<double> distances(static_cast<int64_t>(field.distance.size()));
    py::array_t<int32_t> nearest(static_cast<int64_t>(field.nearest.size()));
    std::copy(field.distance.begin(), field.distance.end(), distances.mutable_data());
    std::copy(field.nearest.begin(), field.nearest.end(), nearest.mutable_data());
    return py::make_tuple(distances, nearest);
  }

  // (vertices (k,), distances (k,), nearest source (k,)) of the vertices of
  // the mesh file within `radius` of the sources (InputQueries::FieldWithin).
  py::tuple FieldWithin(const Faces& faces, const Weights& weights, double radius) const {
    query::RadiusField field;
    {
      py::gil_scoped_release release;
      query::EnginePoints sources;
      ThrowIfError(
          queries_->Read(SpanOf(faces), SpanOf(weights), query::Named("sources"), &sources));
      query::FieldWithinOptions options;
      options.radius = radius;
      query::QueryScratch scratch;
      field = ValueOrThrow(queries_->FieldWithin(sources, options, &scratch));
    }
    const int64_t k = static_cast<int64_t>(field.vertices.size());
    py::array_t<int32_t> vertices(k), nearest(k);
    py::array_t<double> distances(k);
    std::copy(field.vertices.begin(), field.vertices.end(), vertices.mutable_data());
    std::copy(field.distance.begin(), field.distance.end(), distances.mutable_data());
    std::copy(field.nearest.begin(), field.nearest.end(), nearest.mutable_data());
    return py::make_tuple(vertices, distances, nearest);
  }

  // (vertices, r, theta, u, v) of the exponential map round one point.
  py::tuple ExpMap(int32_t face, const Weights& weights, double radius,
                   std::optional<Weights> direction, int near_pairs, double tolerance) const {
    if (weights.size() != 3 || (direction.has_value() && direction->size() != 3)) {
      throw StatusError(absl::InvalidArgumentError("centre and direction need 3 values each"));
    }
    query::ExpMapOptions options;
    options.radius = radius;
    options.distance = DistanceOptionsOf(near_pairs, tolerance);
    if (direction.has_value()) {
      const double* v = direction->data();
      options.reference_direction = mesh::Vec3(v[0], v[1], v[2]);
    }
    const double* w = weights.data();
    const query::SurfacePoint centre{face, {w[0], w[1], w[2]}};
    std::vector<query::ExpMapVertex> map;
    {
      py::gil_scoped_release release;
      // The centre is checked as the server checks it ("center[0]: ...").
      query::EnginePoints checked;
      ThrowIfError(queries_->Read(std::span<const query::SurfacePoint>(&centre, 1),
                                  query::Named("center"), &checked));
      query::QueryScratch scratch;
      map = ValueOrThrow(query::ExpMap(*queries_, checked, 0, options, &scratch));
    }
    const int64_t k = static_cast<int64_t>(map.size());
    py::array_t<int32_t> vertices(k);
    py::array_t<double> r(k), theta(k), u(k), v(k);
    for (int64_t i = 0; i < k; ++i) {
      vertices.mutable_data()[i] = map[i].vertex;
      r.mutable_data()[i] = map[i].r;
      theta.mutable_data()[i] = map[i].theta;
      u.mutable_data()[i] = map[i].u;
      v.mutable_data()[i] = map[i].v;
    }
    return py::make_tuple(vertices, r, theta, u, v);
  }

  // (faces (N,), weights (N, 3), distances (N,)) of the closest points.
  // Vertex ids as surface points (InputQueries::VertexPoint): (faces,
  // weights), the errors naming "name[i]".
  py::tuple VertexPoints(const Faces& ids, const std::string& name) const {
    const int64_t n = ids.size();
    py::array_t<int32_t> faces(n);
    py::array_t<double> weights({n, int64_t{3}});
    int32_t* f = faces.mutable_data();
    double* w = weights.mutable_data();
    const int32_t* v = ids.data();
    {
      py::gil_scoped_release release;
      for (int64_t i = 0; i < n; ++i) {
        absl::StatusOr<query::SurfacePoint> p = queries_->VertexPoint(v[i]);
        if (!p.ok()) {
          ThrowIfError(absl::Status(p.status().code(), absl::StrFormat("%s[%d]: %s", name, i,
                                                                       p.status().message())));
        }
        f[i] = p->face;
        for (int c = 0; c < 3; ++c) w[3 * i + c] = p->w[c];
      }
    }
    return py::make_tuple(faces, weights);
  }

  py::tuple Locate(const Weights& xyz) const {
    const int64_t n = xyz.size() / 3;
    py::array_t<int32_t> faces(n);
    py::array_t<double> weights({n, int64_t{3}}), distances(n);
    int32_t* f = faces.mutable_data();
    double* w = weights.mutable_data();
    double* d = distances.mutable_data();
    const double* x = xyz.data();
    {
      py::gil_scoped_release release;
      std::vector<absl::Status> status(Parts(n));
      ForRanges(n, static_cast<int>(status.size()), [&](int64_t begin, int64_t end, int p) {
        for (int64_t i = begin; i < end && status[p].ok(); ++i) {
          absl::StatusOr<query::LocatedPoint> located =
              queries_->Locate(mesh::Vec3(x[3 * i], x[3 * i + 1], x[3 * i + 2]));
          if (!located.ok()) {
            status[p] =
                absl::Status(located.status().code(),
                             absl::StrFormat("positions[%d]: %s", i, located.status().message()));
            continue;
          }
          f[i] = located->point.face;
          for (int c = 0; c < 3; ++c) w[3 * i + c] = located->point.w[c];
          d[i] = located->distance;
        }
      });
      ThrowIfError(FirstError(status));
    }
    return py::make_tuple(faces, weights, distances);
  }

  // (vertices (V, 3), faces (F, 3)) of the mesh file, as GetMesh sends it.
  py::tuple Mesh() const {
    const int64_t nv = queries_->num_vertices(), nf = queries_->num_faces();
    py::array_t<double> vertices({nv, int64_t{3}});
    py::array_t<int32_t> faces({nf, int64_t{3}});
    // The input's vertices are the index's first ones (copies and midpoints
    // come after).
    const std::span<const double> positions = queries_->index().positions();
    std::copy(positions.begin(), positions.begin() + 3 * nv, vertices.mutable_data());
    int32_t* f = faces.mutable_data();
    for (int32_t i = 0; i < nf; ++i) {
      const mesh::Triangle t = queries_->InputFace(i);
      for (int c = 0; c < 3; ++c) f[3 * i + c] = t[c];
    }
    return py::make_tuple(vertices, faces);
  }

 private:
  // Threads for n items.
  int Parts(int64_t n) const {
    return static_cast<int>(std::clamp<int64_t>(n / kMinItemsPerThread, 1, threads_));
  }

  std::shared_ptr<const query::InputQueries> queries_;
  int threads_ = 1;
};

}  // namespace

void BindIndex(py::module_& m) {
  py::class_<Index>(m, "Index",
                    "An index file answering queries in the mesh file's ids "
                    "(geodex.Index wraps it).")
      .def(py::init<const std::string&, int>(), py::arg("path"), py::arg("threads") = 0)
      .def_property_readonly("num_vertices", &Index::num_vertices)
      .def_property_readonly("num_faces", &Index::num_faces)
      .def_property_readonly("num_samples", &Index::num_samples)
      .def_property_readonly("has_error_bounds", &Index::has_error_bounds)
      .def_property_readonly("report", &Index::report)
      .def_property_readonly("report_json", &Index::report_json)
      .def("distance", &Index::Distance)
      .def("matrix", &Index::Matrix)
      .def("path", &Index::Path)
      .def("field", &Index::Field)
      .def("field_within", &Index::FieldWithin)
      .def("expmap", &Index::ExpMap)
      .def("locate", &Index::Locate)
      .def("vertex_points", &Index::VertexPoints)
      .def("mesh", &Index::Mesh);
}

}  // namespace geodex::python
