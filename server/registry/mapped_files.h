#pragma once

// Names the index file behind a SIGBUS before the server dies of it.
//
// A mapped file that shrinks under its mapping (truncated, or rewritten in
// place by `cp` or a tool that does not publish by rename) turns the next read
// of a lost page into SIGBUS, which no check at load time can prevent and no
// handler can safely recover from: the query reading the page is somewhere
// inside the engine. What the server can do is say which file it was, so that
// the operator knows what to fix; the process then dies with SIGBUS as before
// and its supervisor restarts it, and the restart refuses the damaged file
// (ModelRegistry) while serving everything else.
//
// Thread safety: MappedFileNotice may be created and destroyed from any
// thread; the handler only reads slots that are fully written.

#include <cstdint>
#include <span>
#include <string>

namespace geodex::server {

// Registers one mapped file image for the SIGBUS report while it lives. At
// most kMaxMappedFiles at once; beyond that a file is simply not named.
class MappedFileNotice {
 public:
  static constexpr int kMaxMappedFiles = 4096;

  MappedFileNotice(std::span<const uint8_t> image, const std::string& path);
  ~MappedFileNotice();
  MappedFileNotice(const MappedFileNotice&) = delete;
  MappedFileNotice& operator=(const MappedFileNotice&) = delete;

 private:
  int slot_ = -1;
};

// Installs the SIGBUS handler: it writes "SIGBUS reading <path> at byte <n>
// ..." (or that the address is in no index file) to standard error, then
// dies of the signal with the default action. Call once, from main.
void InstallSigbusReport();

}  // namespace geodex::server
