#pragma once

// The model repository behind one geodex-server: which indexes are served,
// loaded how, and swapped when.
//
// Layout on disk:
//
//   DIR/<model>/<version>/index.gdx    version: a positive decimal integer
//   DIR/<model>/config.textproto       optional (server/config/model_config.proto)
//
// Directories whose name is not a valid model name (ValidateModelName) or
// version, and version directories without an index.gdx yet, are ignored. An
// operator publishes a version by creating its directory with the index
// inside (index::WriteIndexFile renames atomically, so a reader never sees a
// half-written file) and retires one by removing its directory.
//
// Loading. A background thread scans DIR at start, every poll interval and
// whenever TriggerRescan is called (the server's SIGHUP handler). For each
// model it serves the newest `keep_versions` versions (config; default 1) that
// are not known to be broken. A version is loaded with index::Index::Open
// (read-only MAP_SHARED mapping: every server process on the host shares the
// page cache) and query::InputQueries::Create, in the background; the new set
// of served versions is then published as one immutable RegistrySnapshot
// through one shared_ptr. Requests resolve a model against the snapshot
// of the moment and keep it alive until they finish, so a swap never blocks a
// query and in-flight requests complete on the version they started with.
//
// Failures. A version that fails to load (missing, truncated, corrupt, wrong
// format) is remembered by file identity (device, inode, size, mtime) and not
// retried until its file changes; the model's state becomes FAILED with the
// reason, and the versions served before keep serving (or, at start, the
// newest older version that loads). A model whose directory disappears is
// dropped at once (new requests: NOT_FOUND). A served file that changes in
// place (same inode: truncated, or rewritten by a tool that does not rename)
// stops being served at the next scan, since its mapping no longer holds what
// was validated; it is then loaded afresh like any changed file. Between the
// change and that scan a query can still read it (and die of SIGBUS if it
// shrank: server/registry/mapped_files.h).
//
// Thread safety: every public method is safe from any thread. Resolve and
// snapshot() copy the published shared_ptr under a mutex held for that copy
// only. Not std::atomic<std::shared_ptr>: libstdc++ 12 implements it with a
// lock bit ThreadSanitizer cannot follow (it reports a race on every swap),
// and a pthread mutex is just as cheap here, once per call, not per pair.

#include <sys/types.h>

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "core/index/index.h"
#include "core/query/input_queries.h"
#include "server/config/model_config.pb.h"
#include "server/registry/mapped_files.h"

namespace geodex::server {

inline constexpr char kIndexFileName[] = "index.gdx";

// Identity of a file on disk; a change means "reload".
struct FileId {
  dev_t device = 0;
  ino_t inode = 0;
  int64_t size = -1;
  int64_t mtime_ns = 0;
  bool operator==(const FileId&) const = default;
};

// One loaded version of a model. Immutable.
class ServedVersion {
 public:
  // Opens and validates `path` and builds its engine. Errors: those of
  // index::Index::Open and query::InputQueries::Create.
  static absl::StatusOr<std::shared_ptr<const ServedVersion>> Load(int64_t version,
                                                                   const std::string& path,
                                                                   FileId file_id);

  int64_t version() const { return version_; }
  const std::string& path() const { return path_; }
  const FileId& file_id() const { return file_id_; }
  const index::Index& index() const { return *index_; }
  // Bytes of the mapped index file.
  int64_t mapped_bytes() const { return static_cast<int64_t>(index_->size_bytes()); }
  // The queries in the mesh file's ids (what every call answers with); each
  // call chooses how its pairs are refined (query::DistanceOptions).
  const query::InputQueries& queries() const { return *queries_; }

 private:
  ServedVersion() = default;

  int64_t version_ = 0;
  std::string path_;
  FileId file_id_;
  std::shared_ptr<const index::Index> index_;
  std::shared_ptr<const query::InputQueries> queries_;
  // Names this file in a SIGBUS report; released before index_ unmaps it.
  std::unique_ptr<MappedFileNotice> mapped_notice_;
};

enum class LoadState { kLoading, kServing, kFailed };
const char* LoadStateName(LoadState state);

// A model as published in one snapshot. Immutable.
struct ModelSnapshot {
  std::string name;
  LoadState state = LoadState::kLoading;
  std::string reason;                       // why FAILED (or what LOADING waits for)
  std::vector<int64_t> available_versions;  // version directories with an index, ascending
  int64_t loading_version = 0;              // the version being loaded now, 0 if none
  ModelConfig config;
  std::map<int64_t, std::shared_ptr<const ServedVersion>> served;  // by version

  // The newest served version, or nullptr.
  const ServedVersion* newest() const {
    return served.empty() ? nullptr : served.rbegin()->second.get();
  }
};

// Every model at one moment. Immutable.
struct RegistrySnapshot {
  std::map<std::string, std::shared_ptr<const ModelSnapshot>, std::less<>> models;
  bool initial_scan_done = false;
};

// What a request runs against: the version, kept alive (with the rest of the
// model's snapshot) for as long as the request holds this.
struct ResolvedModel {
  std::shared_ptr<const ModelSnapshot> model;
  const ServedVersion* version = nullptr;
};

struct RegistryOptions {
  std::string root;                                  // DIR
  absl::Duration poll_interval = absl::Seconds(10);  // <= 0: no polling
  // Test hook: called on the registry thread before each version loads, with
  // the index path (tests hold a model in LOADING with it).
  std::function<void(const std::string& path)> before_load;
};

class ModelRegistry {
 public:
  // Called on the registry thread after every published change, with the
  // previous and the new snapshot (health status and metrics follow it).
  using Listener =
      std::function<void(const RegistrySnapshot& before, const RegistrySnapshot& after)>;

  // Checks that `options.root` is a readable directory. Errors: NotFound,
  // FailedPrecondition (not a directory), PermissionDenied. Does not scan yet.
  static absl::StatusOr<std::unique_ptr<ModelRegistry>> Create(RegistryOptions options);
  // Stops the background thread (waiting for a load in progress).
  ~ModelRegistry();
  ModelRegistry(const ModelRegistry&) = delete;
  ModelRegistry& operator=(const ModelRegistry&) = delete;

  // Sets the listener; call before Start.
  void SetListener(Listener listener) { listener_ = std::move(listener); }
  // Starts the background thread, which scans at once.
  void Start();
  // Asks for a scan as soon as possible (async-signal-safe: no; call it from
  // a normal thread such as the server's signal thread).
  void TriggerRescan();
  // Asks for a scan and waits until one that started after this call has
  // finished (tests, and tools that want to know a change is live).
  void RescanNow();
  // Stops the background thread. Idempotent.
  void Stop();

  // The current snapshot. Never null.
  std::shared_ptr<const RegistrySnapshot> snapshot() const {
    std::lock_guard<std::mutex> lock(snapshot_mutex_);
    return snapshot_;
  }

  // The model and version a request asks for; `version` 0 is the newest
  // served. Errors: InvalidArgument for a malformed name or a negative
  // version; NotFound for an unknown model or a version that is not served
  // (the message lists the served versions); Unavailable while the model (or
  // the pinned version) is loading, or when it has failed and nothing is
  // served (the message gives the reason).
  absl::StatusOr<ResolvedModel> Resolve(std::string_view name, int64_t version) const;

  const std::string& root() const { return options_.root; }

 private:
  struct VersionEntry {
    FileId disk;                                  // current file on disk
    std::shared_ptr<const ServedVersion> served;  // may hold an older file
    FileId failed_file;                           // the file that failed, if any
    std::string failed_reason;                    // empty: not failed
    bool failed() const { return !failed_reason.empty() && failed_file == disk; }
    bool needs_load() const { return !failed() && !(served && served->file_id() == disk); }
  };
  struct ModelEntry {
    std::string name;
    FileId config_file;
    bool config_loaded = false;  // a config (possibly the default) is in effect
    ModelConfig config;
    std::string config_error;
    std::map<int64_t, VersionEntry> versions;                        // on disk, or still served
    std::map<int64_t, std::shared_ptr<const ServedVersion>> served;  // published set
    int64_t loading_version = 0;
  };

  explicit ModelRegistry(RegistryOptions options);
  void Run();
  void Scan();
  void ScanModel(ModelEntry& entry, const std::string& dir);
  // ScanModel's steps: the configuration, re-read when its file changed;
  // the versions on disk (version -> index file), entry.versions made to
  // agree; the versions that should be served; the served set published
  // (`final`: versions no longer served retired); one version loaded.
  static void ReloadConfig(ModelEntry& entry, const std::string& dir);
  static std::map<int64_t, FileId> ScanVersions(ModelEntry& entry, const std::string& dir);
  static std::vector<int64_t> DesiredVersions(ModelEntry& entry,
                                              const std::map<int64_t, FileId>& disk);
  static void UpdateServed(ModelEntry& entry, const std::map<int64_t, FileId>& disk, bool final);
  void LoadVersion(ModelEntry& entry, int64_t version, const std::string& dir);
  void Publish(bool initial_scan_done);
  std::shared_ptr<const ModelSnapshot> MakeModelSnapshot(const ModelEntry& entry) const;

  const RegistryOptions options_;
  Listener listener_;
  mutable std::mutex snapshot_mutex_;  // guards snapshot_ (the pointer, not the snapshot)
  std::shared_ptr<const RegistrySnapshot> snapshot_;

  // Owned by the registry thread.
  std::map<std::string, ModelEntry, std::less<>> entries_;
  bool initial_scan_done_ = false;

  std::mutex mutex_;  // guards the fields below
  std::condition_variable wake_;
  std::condition_variable scanned_;
  bool stop_ = false;
  uint64_t requested_ = 0;  // scans asked for
  uint64_t completed_ = 0;  // the value of requested_ when the last scan started
  std::thread thread_;
};

}  // namespace geodex::server
