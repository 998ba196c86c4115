#include "server/registry/model_registry.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <set>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "server/config/model_config.h"
#include "spdlog/spdlog.h"

namespace geodex::server {
namespace {

namespace fs = std::filesystem;

// The identity of the regular file at `path`, or nullopt if there is none.
std::optional<FileId> StatRegularFile(const std::string& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return std::nullopt;
  FileId id;
  id.device = st.st_dev;
  id.inode = st.st_ino;
  id.size = st.st_size;
  id.mtime_ns = static_cast<int64_t>(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec;
  return id;
}

// A version directory name: a positive decimal integer without sign or
// leading zeros, at most 18 digits.
std::optional<int64_t> ParseVersion(const std::string& name) {
  if (name.empty() || name.size() > 18 || name[0] == '0') return std::nullopt;
  int64_t v = 0;
  for (char c : name) {
    if (c < '0' || c > '9') return std::nullopt;
    v = v * 10 + (c - '0');
  }
  return v;
}

std::string JoinVersions(const std::vector<int64_t>& versions) {
  return versions.empty() ? "none" : absl::StrJoin(versions, ", ");
}

}  // namespace

// --- ServedVersion ------------------------------------------------------------

absl::StatusOr<std::shared_ptr<const ServedVersion>> ServedVersion::Load(int64_t version,
                                                                         const std::string& path,
                                                                         FileId file_id) {
  auto index = index::Index::Open(path);
  if (!index.ok()) return index.status();
  auto queries = query::InputQueries::Create(*index);
  if (!queries.ok()) return queries.status();
  std::shared_ptr<ServedVersion> served(new ServedVersion());
  served->version_ = version;
  served->path_ = path;
  served->file_id_ = file_id;
  served->index_ = *std::move(index);
  served->queries_ = *std::move(queries);
  served->mapped_notice_ = std::make_unique<MappedFileNotice>(served->index_->image(), path);
  return std::shared_ptr<const ServedVersion>(std::move(served));
}

const char* LoadStateName(LoadState state) {
  switch (state) {
    case LoadState::kLoading:
      return "LOADING";
    case LoadState::kServing:
      return "SERVING";
    case LoadState::kFailed:
      return "FAILED";
  }
  return "UNKNOWN";
}

// --- ModelRegistry --------------------------------------------------------------

absl::StatusOr<std::unique_ptr<ModelRegistry>> ModelRegistry::Create(RegistryOptions options) {
  struct stat st;
  if (::stat(options.root.c_str(), &st) != 0) {
    const int err = errno;
    const std::string message =
        absl::StrFormat("model repository %s: %s", options.root, std::strerror(err));
    if (err == EACCES) return absl::PermissionDeniedError(message);
    return absl::NotFoundError(message);
  }
  if (!S_ISDIR(st.st_mode)) {
    return absl::FailedPreconditionError(
        absl::StrFormat("model repository %s is not a directory", options.root));
  }
  if (::access(options.root.c_str(), R_OK | X_OK) != 0) {
    return absl::PermissionDeniedError(
        absl::StrFormat("model repository %s is not readable", options.root));
  }
  return std::unique_ptr<ModelRegistry>(new ModelRegistry(std::move(options)));
}

ModelRegistry::ModelRegistry(RegistryOptions options)
    : options_(std::move(options)), snapshot_(std::make_shared<const RegistrySnapshot>()) {}

ModelRegistry::~ModelRegistry() { Stop(); }

void ModelRegistry::Start() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (thread_.joinable()) return;
  ++requested_;  // the first scan
  thread_ = std::thread([this] { Run(); });
}

void ModelRegistry::TriggerRescan() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++requested_;
  }
  wake_.notify_one();
}

void ModelRegistry::RescanNow() {
  std::unique_lock<std::mutex> lock(mutex_);
  const uint64_t ticket = ++requested_;
  wake_.notify_one();
  scanned_.wait(lock, [&] { return completed_ >= ticket || stop_ || !thread_.joinable(); });
}

void ModelRegistry::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  scanned_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void ModelRegistry::Run() {
  const auto poll = absl::ToChronoMilliseconds(options_.poll_interval);
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    auto due = [this] { return stop_ || requested_ > completed_; };
    if (poll.count() > 0) {
      wake_.wait_for(lock, poll, due);
    } else {
      wake_.wait(lock, due);
    }
    if (stop_) return;
    const uint64_t ticket = requested_;
    lock.unlock();
    Scan();
    lock.lock();
    completed_ = ticket;
    scanned_.notify_all();
  }
}

void ModelRegistry::Scan() {
  std::error_code ec;
  fs::directory_iterator it(options_.root, ec);
  if (ec) {
    // Keep serving what is loaded: an unreadable repository is more likely a
    // transient problem (remount, permissions) than the removal of every model.
    spdlog::error("model repository {}: {}; keeping the loaded models", options_.root,
                  ec.message());
    return;
  }
  std::set<std::string, std::less<>> seen;
  for (; it != fs::directory_iterator(); it.increment(ec)) {
    if (ec) break;
    const std::string name = it->path().filename().string();
    if (!ValidateModelName(name).ok()) continue;
    std::error_code type_ec;
    if (!fs::is_directory(it->path(), type_ec)) continue;  // follows symlinks
    seen.insert(name);
  }
  if (ec) {
    spdlog::error("model repository {}: {}; keeping the loaded models", options_.root,
                  ec.message());
    return;
  }
  // Removed models go first and at once: a model that is gone must stop
  // answering even if other models take long to load.
  bool removed = false;
  for (auto e = entries_.begin(); e != entries_.end();) {
    if (seen.count(e->first) == 0) {
      spdlog::info("model {} removed from the repository; no longer served", e->first);
      e = entries_.erase(e);
      removed = true;
    } else {
      ++e;
    }
  }
  if (removed) Publish(initial_scan_done_);
  for (const std::string& name : seen) {
    auto [entry, inserted] = entries_.try_emplace(name);
    if (inserted) {
      entry->second.name = name;
      spdlog::info("model {} found in the repository", name);
    }
    ScanModel(entry->second, (fs::path(options_.root) / name).string());
  }
  if (!initial_scan_done_) {
    initial_scan_done_ = true;
  }
  Publish(initial_scan_done_);
}

void ModelRegistry::ReloadConfig(ModelEntry& entry, const std::string& dir) {
  const std::string config_path = (fs::path(dir) / kModelConfigFile).string();
  const FileId config_id = StatRegularFile(config_path).value_or(FileId{});
  if ((entry.config_loaded || !entry.config_error.empty()) && config_id == entry.config_file) {
    return;
  }
  entry.config_file = config_id;
  absl::StatusOr<ModelConfig> config = LoadModelConfig(config_path);
  if (config.ok()) {
    entry.config = *std::move(config);
    entry.config_loaded = true;
    entry.config_error.clear();
  } else {
    entry.config_error = std::string(config.status().message());
    spdlog::warn("model {}: {}{}", entry.name, entry.config_error,
                 entry.config_loaded ? "; keeping the previous configuration" : "");
  }
}

std::map<int64_t, FileId> ModelRegistry::ScanVersions(ModelEntry& entry, const std::string& dir) {
  std::map<int64_t, FileId> disk;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec); !ec && it != fs::directory_iterator();
       it.increment(ec)) {
    const std::optional<int64_t> version = ParseVersion(it->path().filename().string());
    if (!version) continue;
    const std::optional<FileId> id = StatRegularFile((it->path() / kIndexFileName).string());
    if (id) disk[*version] = *id;
  }
  for (auto v = entry.versions.begin(); v != entry.versions.end();) {
    if (disk.count(v->first) == 0) {
      v->second.disk = FileId{};  // gone; kept only while it is served
      if (v->second.served == nullptr) {
        v = entry.versions.erase(v);
        continue;
      }
    }
    ++v;
  }
  for (const auto& [version, id] : disk) {
    VersionEntry& ve = entry.versions[version];
    ve.disk = id;
    // The served file itself changed (same inode, new size or mtime): it was
    // rewritten or truncated in place under its mapping, so what is served
    // is no longer what was validated. Stop serving it now; the file is then
    // loaded afresh below like any changed file (served if it validates).
    if (ve.served && ve.served->file_id() != id && ve.served->file_id().device == id.device &&
        ve.served->file_id().inode == id.inode) {
      spdlog::error(
          "model {} version {}: {} was modified in place while mapped; no longer served "
          "(publish indexes by writing them elsewhere and renaming them into place)",
          entry.name, version, ve.served->path());
      ve.served.reset();
    }
  }
  return disk;
}

// Which versions should be served: the newest keep_versions ones on disk
// that are not known to be broken (a broken file whose previous contents
// are still served counts as served).
std::vector<int64_t> ModelRegistry::DesiredVersions(ModelEntry& entry,
                                                    const std::map<int64_t, FileId>& disk) {
  const size_t keep = std::max<int32_t>(1, entry.config.keep_versions());
  std::vector<int64_t> out;
  for (auto v = disk.rbegin(); v != disk.rend() && out.size() < keep; ++v) {
    const VersionEntry& ve = entry.versions[v->first];
    if (ve.failed() && ve.served == nullptr) continue;
    out.push_back(v->first);
  }
  return out;
}

// Publishes the served set: the desired versions that are loaded; if none
// is, the newest version served so far keeps serving.
void ModelRegistry::UpdateServed(ModelEntry& entry, const std::map<int64_t, FileId>& disk,
                                 bool final) {
  std::map<int64_t, std::shared_ptr<const ServedVersion>> served;
  for (int64_t v : DesiredVersions(entry, disk)) {
    if (entry.versions[v].served) served[v] = entry.versions[v].served;
  }
  if (served.empty()) {
    for (auto v = entry.versions.rbegin(); v != entry.versions.rend(); ++v) {
      if (v->second.served) {
        served[v->first] = v->second.served;
        break;
      }
    }
  }
  if (final) {
    for (auto v = entry.versions.begin(); v != entry.versions.end();) {
      if (served.count(v->first) == 0 && v->second.served) {
        spdlog::info("model {} version {} retired", entry.name, v->first);
        v->second.served.reset();  // freed when the last request using it ends
      }
      if (v->second.served == nullptr && v->second.disk.size < 0) {
        v = entry.versions.erase(v);
      } else {
        ++v;
      }
    }
  }
  entry.served = std::move(served);
}

void ModelRegistry::LoadVersion(ModelEntry& entry, int64_t version, const std::string& dir) {
  VersionEntry& ve = entry.versions[version];
  const std::string path = (fs::path(dir) / std::to_string(version) / kIndexFileName).string();
  entry.loading_version = version;
  Publish(initial_scan_done_);
  if (options_.before_load) options_.before_load(path);
  const auto start = std::chrono::steady_clock::now();
  auto loaded = ServedVersion::Load(version, path, ve.disk);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  entry.loading_version = 0;
  if (loaded.ok()) {
    spdlog::info("model {} version {} loaded: {} vertices, {} samples, {} bytes mapped, {:.3f}s",
                 entry.name, version, (*loaded)->index().num_vertices(),
                 (*loaded)->index().num_samples(), (*loaded)->mapped_bytes(), seconds);
    ve.served = *std::move(loaded);
    ve.failed_reason.clear();
  } else {
    ve.failed_file = ve.disk;
    ve.failed_reason = loaded.status().ToString();
    spdlog::error("model {} version {} failed to load: {}", entry.name, version, ve.failed_reason);
  }
}

void ModelRegistry::ScanModel(ModelEntry& entry, const std::string& dir) {
  // The configuration, re-read when its file changes.
  ReloadConfig(entry, dir);
  // The versions on disk.
  const std::map<int64_t, FileId> disk = ScanVersions(entry, dir);
  if (entry.config_loaded) {
    for (;;) {
      int64_t next = 0;
      for (int64_t v : DesiredVersions(entry, disk)) {
        if (entry.versions[v].needs_load()) {
          next = v;
          break;
        }
      }
      if (next == 0) break;
      LoadVersion(entry, next, dir);
      UpdateServed(entry, disk, /*final=*/false);
      Publish(initial_scan_done_);
    }
  }
  UpdateServed(entry, disk, /*final=*/true);
}

std::shared_ptr<const ModelSnapshot> ModelRegistry::MakeModelSnapshot(
    const ModelEntry& entry) const {
  auto m = std::make_shared<ModelSnapshot>();
  m->name = entry.name;
  m->config = entry.config;
  m->served = entry.served;
  m->loading_version = entry.loading_version;
  for (const auto& [version, ve] : entry.versions) {
    if (ve.disk.size >= 0) m->available_versions.push_back(version);
  }
  const VersionEntry* newest = nullptr;
  if (!m->available_versions.empty()) {
    newest = &entry.versions.at(m->available_versions.back());
  }
  if (!entry.config_error.empty()) {
    m->state = LoadState::kFailed;
    m->reason = "config: " + entry.config_error;
  } else if (newest != nullptr && newest->failed()) {
    m->state = LoadState::kFailed;
    m->reason =
        absl::StrFormat("version %d: %s", m->available_versions.back(), newest->failed_reason);
  } else if (!m->served.empty()) {
    m->state = LoadState::kServing;
  } else {
    m->state = LoadState::kLoading;
    m->reason = m->available_versions.empty()
                    ? absl::StrFormat("no version directory with an %s yet", kIndexFileName)
                    : absl::StrFormat("loading version %d", m->available_versions.back());
  }
  return m;
}

void ModelRegistry::Publish(bool initial_scan_done) {
  auto next = std::make_shared<RegistrySnapshot>();
  next->initial_scan_done = initial_scan_done;
  for (const auto& [name, entry] : entries_) next->models.emplace(name, MakeModelSnapshot(entry));
  std::shared_ptr<const RegistrySnapshot> published = next;
  std::shared_ptr<const RegistrySnapshot> before;
  {
    std::lock_guard<std::mutex> lock(snapshot_mutex_);
    before = std::exchange(snapshot_, published);
  }
  if (listener_) listener_(*before, *published);
}

absl::StatusOr<ResolvedModel> ModelRegistry::Resolve(std::string_view name, int64_t version) const {
  if (absl::Status valid = ValidateModelName(name); !valid.ok()) return valid;
  if (version < 0) {
    return absl::InvalidArgumentError(absl::StrFormat("model version %d is negative", version));
  }
  std::shared_ptr<const RegistrySnapshot> snapshot = this->snapshot();
  auto it = snapshot->models.find(name);
  if (it == snapshot->models.end()) {
    if (!snapshot->initial_scan_done) {
      return absl::UnavailableError("the model repository is still being scanned");
    }
    return absl::NotFoundError(absl::StrFormat("unknown model '%s'", std::string(name)));
  }
  const std::shared_ptr<const ModelSnapshot>& model = it->second;
  std::vector<int64_t> served;
  for (const auto& [v, unused] : model->served) served.push_back(v);
  if (version == 0) {
    if (model->served.empty()) {
      if (model->state == LoadState::kFailed) {
        return absl::UnavailableError(
            absl::StrFormat("model '%s' failed to load: %s", model->name, model->reason));
      }
      return absl::UnavailableError(
          absl::StrFormat("model '%s' is loading (%s)", model->name, model->reason));
    }
    return ResolvedModel{model, model->newest()};
  }
  auto v = model->served.find(version);
  if (v != model->served.end()) return ResolvedModel{model, v->second.get()};
  if (model->loading_version == version) {
    return absl::UnavailableError(
        absl::StrFormat("model '%s' version %d is loading", model->name, version));
  }
  return absl::NotFoundError(
      absl::StrFormat("model '%s' has no served version %d (served: %s; on disk: %s)", model->name,
                      version, JoinVersions(served), JoinVersions(model->available_versions)));
}

}  // namespace geodex::server
