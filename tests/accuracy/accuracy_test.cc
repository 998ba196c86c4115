// CI-sized accuracy run on generated shapes: fails when accuracy regresses.

#include "tests/accuracy/accuracy.h"

#include "core/build/builder.h"
#include "core/mesh/generators.h"
#include "gtest/gtest.h"

namespace geodex::accuracy {
namespace {

namespace gen = mesh::gen;

AccuracyReport Measure(const mesh::Mesh& m, int32_t samples, int32_t points, int32_t sources) {
  build::BuildOptions build_options;
  build_options.num_samples = samples;
  build_options.threads = 2;
  build::BuildSummary summary;
  auto data = build::BuildIndex(m, build_options, &summary);
  EXPECT_TRUE(data.ok()) << data.status();
  auto index = index::Index::FromBytes(*index::SerializeIndex(*data));
  EXPECT_TRUE(index.ok());
  auto engine = query::QueryEngine::Create(*index);
  query::QueryOptions exact;
  exact.exact_near_pairs = true;
  auto exact_engine = query::QueryEngine::Create(*index, exact);
  AccuracyOptions options;
  options.num_points = points;
  options.num_sources = sources;
  options.num_paths = 60;
  const AccuracyReport report = MeasureAccuracy(m, **engine, exact_engine->get(), options);
  std::printf("%s%s", AccuracyReport::MarkdownHeader().c_str(),
              report.ToMarkdownRow(m.name() + " m=" + std::to_string(samples)).c_str());
  return report;
}

TEST(AccuracyTest, DevelopableSurfacesAreExact) {
  for (const mesh::Mesh& m : {gen::FoldedSheet(32, 20, 2.0, 1.0, 1.1)}) {
    const AccuracyReport r = Measure(m, 60, 200, 10);
    EXPECT_LT(r.all.max, 1e-5);
  }
}

TEST(AccuracyTest, SphereAndTorus) {
  {
    const AccuracyReport r = Measure(gen::Sphere(5, 1.0), 200, 300, 10);
    EXPECT_LT(r.all.rms, 0.005);
    EXPECT_LT(r.far.p99, 0.01);
    EXPECT_LT(r.near_exact_mode.max, 1e-6);
    EXPECT_LT(r.all.rms, r.baseline.rms);
    EXPECT_LT(r.path_ratio.p99, 0.02);
  }
  {
    const AccuracyReport r = Measure(gen::Torus(96, 48, 2.0, 0.7), 200, 300, 10);
    EXPECT_LT(r.all.rms, 0.01);
    EXPECT_LT(r.all.rms, r.baseline.rms);
  }
}

}  // namespace
}  // namespace geodex::accuracy
