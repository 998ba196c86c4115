#include "geodex/client/client.h"

#include <array>
#include <atomic>
#include <deque>
#include <functional>
#include <limits>
#include <thread>

#include "absl/synchronization/mutex.h"
#include "geodex/client/mocks/mock_geodex_connection.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"

namespace geodex::client {
namespace {

using ::testing::_;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Return;

// Pair i has a.face = i, so a test distance law of d = a.face identifies the
// pair an answer belongs to.
std::vector<PointPair> NumberedPairs(size_t n) {
  std::vector<PointPair> pairs(n);
  for (size_t i = 0; i < n; ++i) {
    pairs[i].a = {static_cast<int32_t>(i), {0.5, 0.25, 0.25}};
    pairs[i].b = {7, {0, 1, 0}};
  }
  return pairs;
}

// A DistanceStream that answers every batch with d = a.face, the way a server
// would: results in batch order, each after its batch was written. Safe for
// one writer thread and one reader thread. Can break after a number of
// answers, or reject one batch.
class FakeStream : public DistanceStream {
 public:
  struct Script {
    int break_after_answers = -1;  // >= 0: Read fails after that many answers
    absl::Status break_status = absl::UnavailableError("connection reset");
    int64_t reject_batch = -1;  // this batch_id gets a per-batch error
    absl::Status reject_status = absl::InvalidArgumentError("a[5]: weights sum to 2");
  };

  explicit FakeStream(Script script) : script_(std::move(script)) {}

  bool Write(const v1::DistanceBatch& batch) override {
    absl::MutexLock lock(&mu_);
    if (broken_ || cancelled_) return false;
    batches_.push_back(batch);
    pending_.push_back(batch);
    return true;
  }
  bool WritesDone() override {
    absl::MutexLock lock(&mu_);
    writes_done_ = true;
    return !broken_;
  }
  bool Read(v1::DistanceResult* result) override {
    absl::MutexLock lock(&mu_);
    if (script_.break_after_answers >= 0 && answered_ >= script_.break_after_answers) {
      broken_ = true;
      return false;
    }
    auto ready = [this] { return !pending_.empty() || writes_done_ || cancelled_; };
    mu_.Await(absl::Condition(&ready));
    if (cancelled_ || pending_.empty()) return false;
    const v1::DistanceBatch batch = pending_.front();
    pending_.pop_front();
    result->Clear();
    result->set_batch_id(batch.batch_id());
    result->set_version(3);
    if (static_cast<int64_t>(batch.batch_id()) == script_.reject_batch) {
      result->set_error_code(static_cast<int>(script_.reject_status.code()));
      result->set_error_message(std::string(script_.reject_status.message()));
    } else {
      for (int32_t face : batch.a().faces()) result->add_distances(face);
    }
    ++answered_;
    return true;
  }
  void Cancel() override {
    absl::MutexLock lock(&mu_);
    cancelled_ = true;
  }
  absl::Status Finish() override {
    absl::MutexLock lock(&mu_);
    if (broken_) return script_.break_status;
    if (cancelled_) return absl::CancelledError("cancelled");
    return absl::OkStatus();
  }

  std::vector<v1::DistanceBatch> batches() const {
    absl::MutexLock lock(&mu_);
    return batches_;
  }

 private:
  Script script_;
  mutable absl::Mutex mu_;
  std::vector<v1::DistanceBatch> batches_;
  std::deque<v1::DistanceBatch> pending_;
  int answered_ = 0;
  bool writes_done_ = false, cancelled_ = false, broken_ = false;
};

// Lets a test keep the FakeStream (and inspect it) after the client is done
// with the stream it was given.
class Proxy : public DistanceStream {
 public:
  explicit Proxy(FakeStream* s) : s_(s) {}
  bool Write(const v1::DistanceBatch& b) override { return s_->Write(b); }
  bool WritesDone() override { return s_->WritesDone(); }
  bool Read(v1::DistanceResult* r) override { return s_->Read(r); }
  void Cancel() override { s_->Cancel(); }
  absl::Status Finish() override { return s_->Finish(); }

 private:
  FakeStream* s_;
};

// Hands out FakeStreams with the given scripts in order (the last one
// repeats).
class StreamFactory {
 public:
  explicit StreamFactory(std::vector<FakeStream::Script> scripts) : scripts_(std::move(scripts)) {}

  std::unique_ptr<DistanceStream> operator()(const StreamOptions&) {
    const FakeStream::Script& script = scripts_[std::min(opened_, scripts_.size() - 1)];
    ++opened_;
    return std::make_unique<FakeStream>(script);
  }

 private:
  std::vector<FakeStream::Script> scripts_;
  size_t opened_ = 0;
};

ClientOptions SmallBatches(int batch_size) {
  ClientOptions options;
  options.batch_size = batch_size;
  options.retry.initial_backoff = absl::Microseconds(10);
  options.retry.max_backoff = absl::Microseconds(100);
  return options;
}

TEST(ClientDistance, OneBatchIsOneUnaryCall) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, StreamDistances).Times(0);
  EXPECT_CALL(*mock, Distance).WillOnce([](const v1::DistanceRequest& r) {
    EXPECT_EQ(r.model().name(), "torus");
    EXPECT_EQ(r.model().version(), 2);
    EXPECT_EQ(r.near_pairs(), v1::NEAR_PAIRS_UNFOLD);
    EXPECT_FALSE(r.exact_near_pairs());  // deprecated: the client sends near_pairs
    EXPECT_THAT(r.a().faces(), ElementsAre(0, 1, 2));
    EXPECT_THAT(r.a().weights(), ElementsAre(0.5, 0.25, 0.25, 0.5, 0.25, 0.25, 0.5, 0.25, 0.25));
    EXPECT_THAT(r.b().faces(), ElementsAre(7, 7, 7));
    v1::DistanceResponse response;
    for (int f : r.a().faces()) response.add_distances(f + 0.5);
    return response;
  });
  Client client(mock, SmallBatches(3));
  absl::StatusOr<std::vector<double>> d =
      client.Distance(ModelRef("torus", 2), NumberedPairs(3), NearPairs::kUnfold);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_THAT(*d, ElementsAre(0.5, 1.5, 2.5));
}

// Vertex points go out as vertex ids: alone when every point of a side is a
// vertex, beside the faces (-1 for a face point) when a side mixes both.
TEST(ClientDistance, VertexPointsAreSentAsVertexIds) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Distance).WillOnce([](const v1::DistanceRequest& r) {
    EXPECT_THAT(r.a().vertices(), ElementsAre(4, 9));
    EXPECT_TRUE(r.a().faces().empty());
    EXPECT_TRUE(r.a().weights().empty());
    EXPECT_THAT(r.b().vertices(), ElementsAre(-1, 12));
    EXPECT_THAT(r.b().faces(), ElementsAre(3, 0));
    EXPECT_EQ(r.b().weights_size(), 6);
    EXPECT_EQ(r.b().weights(0), 0.2);
    v1::DistanceResponse response;
    response.add_distances(1);
    response.add_distances(2);
    return response;
  });
  Client client(mock, SmallBatches(8));
  const std::vector<PointPair> pairs = {
      {SurfacePoint::Vertex(4), SurfacePoint{3, {0.2, 0.3, 0.5}}},
      {SurfacePoint::Vertex(9), SurfacePoint::Vertex(12)}};
  absl::StatusOr<std::vector<double>> d = client.Distance(ModelRef("torus"), pairs);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_THAT(*d, ElementsAre(1, 2));
}

TEST(ClientDistance, ToleranceThresholdAndBoundsAreSentAndBoundsReturned) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Distance).WillOnce([](const v1::DistanceRequest& r) {
    EXPECT_EQ(r.tolerance(), 0.005);
    EXPECT_TRUE(r.error_bounds());
    EXPECT_EQ(r.refine_below(), 8);
    EXPECT_EQ(r.near_pairs(), v1::NEAR_PAIRS_UNSPECIFIED);
    v1::DistanceResponse response;
    for (int f : r.a().faces()) {
      response.add_distances(f + 0.5);
      response.add_bounds(0.01 * f);
    }
    return response;
  });
  Client client(mock, SmallBatches(3));
  absl::StatusOr<Distances> d =
      client.Distance("torus", NumberedPairs(3),
                      {.tolerance = 0.005, .error_bounds = true, .refine_below = 8});
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_THAT(d->distance, ElementsAre(0.5, 1.5, 2.5));
  EXPECT_THAT(d->bound, ElementsAre(0, 0.01, 0.02));
}

TEST(ClientDistance, MissingBoundsAreDataLoss) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Distance).WillOnce([](const v1::DistanceRequest& r) {
    v1::DistanceResponse response;
    for (int f : r.a().faces()) response.add_distances(f);
    return response;
  });
  Client client(mock, SmallBatches(3));
  EXPECT_EQ(client.Distance("torus", NumberedPairs(3), {.error_bounds = true}).status().code(),
            absl::StatusCode::kDataLoss);
}

TEST(ClientDistance, ManyPairsAreBatchedOverOneStreamInInputOrder) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Distance).Times(0);
  EXPECT_CALL(*mock, StreamDistances).WillOnce([&](const StreamOptions& options) {
    EXPECT_FALSE(options.deadline.has_value());  // the connection's default
    return std::make_unique<FakeStream>(FakeStream::Script{});
  });
  Client client(mock, SmallBatches(1000));
  const size_t n = 10007;
  absl::StatusOr<std::vector<double>> d = client.Distance("torus", NumberedPairs(n));
  ASSERT_TRUE(d.ok()) << d.status();
  ASSERT_EQ(d->size(), n);
  for (size_t i = 0; i < n; ++i) ASSERT_EQ((*d)[i], static_cast<double>(i)) << i;
}

TEST(ClientDistance, BatchesAreSizedNumberedAndOnlyTheFirstNamesTheModel) {
  auto mock = std::make_shared<MockGeodexConnection>();
  FakeStream fake{FakeStream::Script{}};
  EXPECT_CALL(*mock, StreamDistances).WillOnce([&](const StreamOptions&) {
    return std::make_unique<Proxy>(&fake);
  });
  Client client(mock, SmallBatches(100));
  ASSERT_TRUE(client
                  .Distance(ModelRef("torus", 4), NumberedPairs(250),
                            DistanceQuery{.near_pairs = NearPairs::kExact, .refine_below = 4})
                  .ok());
  const std::vector<v1::DistanceBatch> batches = fake.batches();
  ASSERT_EQ(batches.size(), 3u);
  EXPECT_EQ(batches[0].model().name(), "torus");
  EXPECT_EQ(batches[0].model().version(), 4);
  for (size_t k = 0; k < batches.size(); ++k) {
    EXPECT_EQ(batches[k].batch_id(), k);
    EXPECT_EQ(batches[k].near_pairs(), v1::NEAR_PAIRS_EXACT);
    EXPECT_EQ(batches[k].refine_below(), 4);
    if (k > 0) {
      EXPECT_TRUE(batches[k].model().name().empty()) << k;
    }
  }
  EXPECT_EQ(batches[0].a().faces_size(), 100);
  EXPECT_EQ(batches[2].a().faces_size(), 50);
  EXPECT_EQ(batches[2].a().faces(0), 200);
  EXPECT_EQ(batches[2].b().weights_size(), 150);
}

TEST(ClientDistance, BrokenStreamIsResumedFromTheFirstUnansweredBatch) {
  auto mock = std::make_shared<MockGeodexConnection>();
  FakeStream::Script breaks;
  breaks.break_after_answers = 3;
  StreamFactory factory({breaks, FakeStream::Script{}});
  EXPECT_CALL(*mock, StreamDistances).Times(2).WillRepeatedly([&](const StreamOptions& o) {
    return factory(o);
  });
  Client client(mock, SmallBatches(10));
  absl::StatusOr<std::vector<double>> d = client.Distance("torus", NumberedPairs(95));
  ASSERT_TRUE(d.ok()) << d.status();
  for (size_t i = 0; i < 95; ++i) ASSERT_EQ((*d)[i], static_cast<double>(i));
}

TEST(ClientDistance, ResumedStreamNamesTheModelAndStartsAtTheUnansweredBatch) {
  auto mock = std::make_shared<MockGeodexConnection>();
  FakeStream::Script breaks;
  breaks.break_after_answers = 2;
  FakeStream first(breaks), second(FakeStream::Script{});
  EXPECT_CALL(*mock, StreamDistances)
      .WillOnce([&](const StreamOptions&) { return std::make_unique<Proxy>(&first); })
      .WillOnce([&](const StreamOptions&) { return std::make_unique<Proxy>(&second); });
  Client client(mock, SmallBatches(10));
  ASSERT_TRUE(client.Distance("torus", NumberedPairs(50)).ok());
  const std::vector<v1::DistanceBatch> resent = second.batches();
  ASSERT_EQ(resent.size(), 3u);
  EXPECT_EQ(resent[0].batch_id(), 2u);
  EXPECT_EQ(resent[0].model().name(), "torus");
  EXPECT_EQ(resent[0].a().faces(0), 20);
  EXPECT_EQ(resent[2].batch_id(), 4u);
}

TEST(ClientDistance, RejectedBatchFailsTheCallNamingItsPairsWithoutRetry) {
  auto mock = std::make_shared<MockGeodexConnection>();
  FakeStream::Script rejects;
  rejects.reject_batch = 2;
  StreamFactory factory({rejects});
  EXPECT_CALL(*mock, StreamDistances).WillOnce([&](const StreamOptions& o) { return factory(o); });
  Client client(mock, SmallBatches(100));
  absl::StatusOr<std::vector<double>> d = client.Distance("torus", NumberedPairs(1000));
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(d.status().message(), "pairs [200, 300): a[5]: weights sum to 2");
}

TEST(ClientDistance, BatchUnavailableWhileLoadingIsRetried) {
  auto mock = std::make_shared<MockGeodexConnection>();
  FakeStream::Script loading;
  loading.reject_batch = 0;
  loading.reject_status = absl::UnavailableError("model torus is loading");
  StreamFactory factory({loading, loading, FakeStream::Script{}});
  EXPECT_CALL(*mock, StreamDistances).Times(3).WillRepeatedly([&](const StreamOptions& o) {
    return factory(o);
  });
  Client client(mock, SmallBatches(10));
  absl::StatusOr<std::vector<double>> d = client.Distance("torus", NumberedPairs(30));
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ((*d)[29], 29);
}

TEST(ClientDistance, GivesUpAfterMaxAttemptsWithoutProgress) {
  auto mock = std::make_shared<MockGeodexConnection>();
  FakeStream::Script dead;
  dead.break_after_answers = 0;
  StreamFactory factory({dead});
  ClientOptions options = SmallBatches(10);
  options.retry.max_attempts = 3;
  EXPECT_CALL(*mock, StreamDistances).Times(3).WillRepeatedly([&](const StreamOptions& o) {
    return factory(o);
  });
  Client client(mock, options);
  absl::StatusOr<std::vector<double>> d = client.Distance("torus", NumberedPairs(30));
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(d.status().message(), HasSubstr("gave up after 3 attempts"));
}

TEST(ClientDistance, StreamErrorOtherThanUnavailableIsNotRetried) {
  auto mock = std::make_shared<MockGeodexConnection>();
  FakeStream::Script denied;
  denied.break_after_answers = 1;
  denied.break_status = absl::PermissionDeniedError("no");
  StreamFactory factory({denied});
  EXPECT_CALL(*mock, StreamDistances).WillOnce([&](const StreamOptions& o) { return factory(o); });
  Client client(mock, SmallBatches(10));
  absl::StatusOr<std::vector<double>> d = client.Distance("torus", NumberedPairs(30));
  EXPECT_EQ(d.status(), absl::PermissionDeniedError("no"));
}

TEST(ClientDistance, UnaryErrorsKeepTheServersCodeAndMessage) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Distance).WillOnce(Return(absl::NotFoundError("model 'nope' not found")));
  Client client(mock);
  EXPECT_EQ(client.Distance("nope", NumberedPairs(2)).status(),
            absl::NotFoundError("model 'nope' not found"));
}

TEST(ClientDistance, WrongNumberOfDistancesIsDataLoss) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Distance).WillOnce(Return(v1::DistanceResponse()));
  Client client(mock);
  EXPECT_EQ(client.Distance("torus", NumberedPairs(2)).status().code(),
            absl::StatusCode::kDataLoss);
}

TEST(ClientDistance, NoPairsNoCallsAndNoModelIsInvalid) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Distance).Times(0);
  EXPECT_CALL(*mock, StreamDistances).Times(0);
  Client client(mock);
  ASSERT_TRUE(client.Distance("torus", {}).ok());
  EXPECT_TRUE(client.Distance("torus", {})->empty());
  EXPECT_EQ(client.Distance("", NumberedPairs(1)).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(client.Distance(ModelRef("torus", -1), NumberedPairs(1)).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(ClientDistance, ConcurrentCallsOnOneClient) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, StreamDistances).WillRepeatedly([](const StreamOptions&) {
    return std::make_unique<FakeStream>(FakeStream::Script{});
  });
  EXPECT_CALL(*mock, Distance).WillRepeatedly([](const v1::DistanceRequest& r) {
    v1::DistanceResponse response;
    for (int f : r.a().faces()) response.add_distances(f);
    return response;
  });
  const Client client(mock, SmallBatches(64));
  std::atomic<int> failures{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      for (int k = 0; k < 20; ++k) {
        const size_t n = 1 + (t * 37 + k * 101) % 700;
        absl::StatusOr<std::vector<double>> d = client.Distance("torus", NumberedPairs(n));
        if (!d.ok() || d->size() != n || d->back() != n - 1.0) ++failures;
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(failures.load(), 0);
}

TEST(DistanceSession, SendsReadsInOrderWithPerBatchStatus) {
  auto mock = std::make_shared<MockGeodexConnection>();
  FakeStream::Script script;
  script.reject_batch = 1;
  EXPECT_CALL(*mock, StreamDistances).WillOnce([&](const StreamOptions& options) {
    EXPECT_EQ(options.deadline, absl::InfiniteDuration());
    return std::make_unique<FakeStream>(script);
  });
  Client client(mock);
  DistanceSession session = client.OpenDistanceSession("torus");
  const std::vector<PointPair> pairs = NumberedPairs(6);
  for (uint64_t k = 0; k < 3; ++k) {
    absl::StatusOr<uint64_t> id = session.Send(absl::MakeConstSpan(pairs).subspan(2 * k, 2));
    ASSERT_TRUE(id.ok()) << id.status();
    EXPECT_EQ(*id, k);
  }
  session.CloseSend();
  EXPECT_EQ(session.Send(pairs).status().code(), absl::StatusCode::kFailedPrecondition);
  std::vector<DistanceBatchResult> results;
  while (std::optional<DistanceBatchResult> r = session.Read()) results.push_back(*r);
  ASSERT_EQ(results.size(), 3u);
  EXPECT_THAT(results[0].distances, ElementsAre(0, 1));
  EXPECT_EQ(results[0].version, 3);
  EXPECT_EQ(results[1].status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(results[2].distances, ElementsAre(4, 5));
  EXPECT_EQ(results[2].batch_id, 2u);
  EXPECT_TRUE(session.Finish().ok());
}

TEST(DistanceSession, EveryBatchCarriesTheSessionsOptions) {
  auto mock = std::make_shared<MockGeodexConnection>();
  auto stream = std::make_unique<MockDistanceStream>();
  std::vector<v1::DistanceBatch> written;
  EXPECT_CALL(*stream, Write).Times(2).WillRepeatedly([&](const v1::DistanceBatch& b) {
    written.push_back(b);
    return true;
  });
  EXPECT_CALL(*stream, Cancel).Times(::testing::AnyNumber());
  EXPECT_CALL(*mock, StreamDistances).WillOnce(Return(::testing::ByMove(std::move(stream))));
  Client client(mock);
  DistanceSession session = client.OpenDistanceSession(
      "torus", {.near_pairs = NearPairs::kExact, .refine_below = 8});
  ASSERT_TRUE(session.Send(NumberedPairs(2)).ok());
  ASSERT_TRUE(session.Send(NumberedPairs(1)).ok());
  ASSERT_EQ(written.size(), 2u);
  for (const v1::DistanceBatch& b : written) {
    EXPECT_EQ(b.near_pairs(), v1::NEAR_PAIRS_EXACT);
    EXPECT_EQ(b.refine_below(), 8);
  }
  EXPECT_EQ(written[0].model().name(), "torus");
  EXPECT_TRUE(written[1].model().name().empty());  // the stream keeps the first batch's
}

TEST(DistanceSession, BrokenStreamFailsSendAndFinishSaysWhy) {
  auto mock = std::make_shared<MockGeodexConnection>();
  auto stream = std::make_unique<MockDistanceStream>();
  EXPECT_CALL(*stream, Write).WillOnce(Return(false));
  EXPECT_CALL(*stream, Read).WillOnce(Return(false));
  EXPECT_CALL(*stream, Finish).WillOnce(Return(absl::UnavailableError("reset")));
  EXPECT_CALL(*mock, StreamDistances).WillOnce(Return(::testing::ByMove(std::move(stream))));
  Client client(mock);
  DistanceSession session = client.OpenDistanceSession("torus");
  EXPECT_EQ(session.Send(NumberedPairs(1)).status().code(), absl::StatusCode::kUnavailable);
  session.CloseSend();
  EXPECT_FALSE(session.Read().has_value());
  EXPECT_EQ(session.Finish(), absl::UnavailableError("reset"));
}

TEST(ClientMatrix, BlocksAreAssembledByOffset) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Matrix).WillOnce([](const v1::MatrixRequest& r) {
    EXPECT_EQ(r.sources().faces_size(), 3);
    EXPECT_EQ(r.targets().faces_size(), 2);
    EXPECT_EQ(r.near_pairs(), v1::NEAR_PAIRS_PATH);
    std::vector<v1::MatrixBlock> blocks(2);
    blocks[0].set_row_offset(2);
    blocks[0].set_rows(1);
    blocks[0].set_num_targets(2);
    blocks[0].add_values(20);
    blocks[0].add_values(21);
    blocks[1].set_row_offset(0);
    blocks[1].set_rows(2);
    blocks[1].set_num_targets(2);
    for (double v : {0, 1, 10, 11}) blocks[1].add_values(v);
    blocks[1].set_version(5);
    return blocks;
  });
  Client client(mock);
  std::vector<SurfacePoint> sources(3), targets(2);
  absl::StatusOr<DistanceMatrix> m = client.Matrix("torus", sources, targets, NearPairs::kPath);
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->rows, 3);
  EXPECT_EQ(m->cols, 2);
  EXPECT_THAT(m->values, ElementsAre(0, 1, 10, 11, 20, 21));
  EXPECT_EQ(m->At(2, 1), 21);
  EXPECT_EQ(m->version, 5);
}

TEST(ClientMatrix, MissingOrRepeatedRowsAreDataLoss) {
  auto mock = std::make_shared<MockGeodexConnection>();
  v1::MatrixBlock block;
  block.set_row_offset(0);
  block.set_rows(1);
  block.set_num_targets(1);
  block.add_values(1);
  EXPECT_CALL(*mock, Matrix)
      .WillOnce(Return(std::vector<v1::MatrixBlock>{block}))
      .WillOnce(Return(std::vector<v1::MatrixBlock>{block, block}));
  Client client(mock);
  std::vector<SurfacePoint> two(2), one(1);
  EXPECT_EQ(client.Matrix("torus", two, one).status().code(), absl::StatusCode::kDataLoss);
  EXPECT_EQ(client.Matrix("torus", two, one).status().code(), absl::StatusCode::kDataLoss);
}

TEST(ClientPath, SplitIntoCallsAndConverted) {
  auto mock = std::make_shared<MockGeodexConnection>();
  int calls = 0;
  EXPECT_CALL(*mock, Path).Times(3).WillRepeatedly([&](const v1::PathRequest& r) {
    ++calls;
    EXPECT_EQ(r.exact_corridor(), 5u);
    v1::PathResponse response;
    for (int i = 0; i < r.a().faces_size(); ++i) {
      v1::Polyline* line = response.add_paths();
      line->mutable_points()->add_faces(r.a().faces(i));
      for (int k = 0; k < 3; ++k) line->mutable_points()->add_weights(r.a().weights(3 * i + k));
      line->mutable_points()->add_faces(r.b().faces(i));
      for (int k = 0; k < 3; ++k) line->mutable_points()->add_weights(r.b().weights(3 * i + k));
      for (double c : {1.0, 2.0, 3.0, 4.0, 5.0, 6.0}) line->mutable_positions()->add_xyz(c);
      line->set_length(r.a().faces(i));
    }
    return response;
  });
  ClientOptions options;
  options.path_batch_size = 4;
  Client client(mock, options);
  absl::StatusOr<std::vector<GeodesicPath>> paths = client.Path("torus", NumberedPairs(10), 5);
  ASSERT_TRUE(paths.ok()) << paths.status();
  ASSERT_EQ(paths->size(), 10u);
  EXPECT_EQ((*paths)[9].length, 9);
  EXPECT_EQ((*paths)[9].points[0].face, 9);
  EXPECT_EQ((*paths)[9].points[1], (SurfacePoint{7, {0, 1, 0}}));
  EXPECT_EQ((*paths)[9].positions[1], (Position{4, 5, 6}));
}

TEST(ClientPath, PositionsNotMatchingPointsIsDataLoss) {
  auto mock = std::make_shared<MockGeodexConnection>();
  v1::PathResponse response;
  v1::Polyline* line = response.add_paths();
  line->mutable_points()->add_faces(1);
  for (int k = 0; k < 3; ++k) line->mutable_points()->add_weights(1.0 / 3);
  EXPECT_CALL(*mock, Path).WillOnce(Return(response));
  Client client(mock);
  EXPECT_EQ(client.Path("torus", NumberedPairs(1)).status().code(), absl::StatusCode::kDataLoss);
}

TEST(ClientLocate, ChunkedAndInOrder) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, Locate).Times(2).WillRepeatedly([](const v1::LocateRequest& r) {
    v1::LocateResponse response;
    for (int i = 0; i < r.positions().xyz_size(); i += 3) {
      response.mutable_points()->add_faces(static_cast<int>(r.positions().xyz(i)));
      for (double w : {1.0, 0.0, 0.0}) response.mutable_points()->add_weights(w);
      response.add_distances(r.positions().xyz(i + 1));
    }
    return response;
  });
  ClientOptions options;
  options.locate_batch_size = 3;
  Client client(mock, options);
  std::vector<Position> positions;
  for (int i = 0; i < 5; ++i) positions.push_back({double(i), 0.5 * i, 0});
  absl::StatusOr<std::vector<LocatedPoint>> located = client.Locate("torus", positions);
  ASSERT_TRUE(located.ok()) << located.status();
  ASSERT_EQ(located->size(), 5u);
  EXPECT_EQ((*located)[4].point.face, 4);
  EXPECT_EQ((*located)[4].distance, 2.0);
}

TEST(ClientModels, ConvertedFromProto) {
  auto mock = std::make_shared<MockGeodexConnection>();
  v1::ListModelsResponse response;
  v1::ModelInfo* m = response.add_models();
  m->set_name("torus");
  m->set_version(3);
  m->add_available_versions(2);
  m->add_available_versions(3);
  m->set_state(v1::ModelInfo::SERVING);
  m->set_num_faces(9216);
  for (double v : {-2.7, -2.7, -0.7}) m->add_bbox_min(v);
  (*m->mutable_build_report())["samples"] = "200";
  v1::ModelInfo* failed = response.add_models();
  failed->set_name("broken");
  failed->set_state(v1::ModelInfo::FAILED);
  failed->set_reason("checksum mismatch");
  EXPECT_CALL(*mock, ListModels).WillOnce(Return(response));
  Client client(mock);
  absl::StatusOr<std::vector<ModelInfo>> models = client.ListModels();
  ASSERT_TRUE(models.ok());
  ASSERT_EQ(models->size(), 2u);
  EXPECT_EQ((*models)[0].name, "torus");
  EXPECT_THAT((*models)[0].available_versions, ElementsAre(2, 3));
  EXPECT_EQ((*models)[0].state, ModelInfo::State::kServing);
  EXPECT_EQ((*models)[0].num_faces, 9216);
  EXPECT_EQ((*models)[0].bbox_min, (Position{-2.7, -2.7, -0.7}));
  EXPECT_EQ((*models)[0].build_report.at("samples"), "200");
  EXPECT_EQ((*models)[1].state, ModelInfo::State::kFailed);
  EXPECT_EQ((*models)[1].reason, "checksum mismatch");
  EXPECT_STREQ(StateName((*models)[1].state), "FAILED");
}

TEST(ClientModels, GetModelPassesTheServersError) {
  auto mock = std::make_shared<MockGeodexConnection>();
  EXPECT_CALL(*mock, GetModel).WillOnce([](const v1::GetModelRequest& r) {
    EXPECT_EQ(r.model().name(), "nope");
    return absl::NotFoundError("model 'nope' not found");
  });
  Client client(mock);
  EXPECT_EQ(client.GetModel("nope").status(), absl::NotFoundError("model 'nope' not found"));
}

// A hand-written connection with no gMock, as a consumer might write.
TEST(GeodexConnection, UnimplementedByDefault) {
  class Empty : public GeodexConnection {};
  Client client(std::make_shared<Empty>());
  EXPECT_EQ(client.ListModels().status().code(), absl::StatusCode::kUnimplemented);
  EXPECT_EQ(client.Distance("torus", NumberedPairs(5000)).status().code(),
            absl::StatusCode::kUnimplemented);
  EXPECT_EQ(client.GetMesh("torus").status().code(), absl::StatusCode::kUnimplemented);
  EXPECT_EQ(client.connection()->GetTriangulation({}).status().code(),
            absl::StatusCode::kUnimplemented);
}

}  // namespace
}  // namespace geodex::client
