#include "server/registry/mapped_files.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstring>

namespace geodex::server {
namespace {

// A slot is claimed (kFree -> kWriting) by one thread, filled, then published
// (kReady, release); the handler reads only kReady slots (acquire). Plain
// fixed-size storage: the handler may not allocate or lock.
enum SlotState : int { kFree = 0, kWriting = 1, kReady = 2 };
struct Slot {
  std::atomic<int> state{kFree};
  uintptr_t begin = 0;
  uintptr_t end = 0;
  char path[512] = {};
};
Slot slots[MappedFileNotice::kMaxMappedFiles];

void WriteAll(const char* text, size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(STDERR_FILENO, text, n);
    if (w <= 0) return;
    text += w;
    n -= static_cast<size_t>(w);
  }
}
void WriteText(const char* text) { WriteAll(text, std::strlen(text)); }
void WriteNumber(uint64_t value) {
  char digits[24];
  int n = 0;
  do {
    digits[sizeof(digits) - 1 - n++] = static_cast<char>('0' + value % 10);
    value /= 10;
  } while (value != 0);
  WriteAll(digits + sizeof(digits) - n, static_cast<size_t>(n));
}

void OnSigbus(int signal, siginfo_t* info, void*) {
  const uintptr_t address = reinterpret_cast<uintptr_t>(info->si_addr);
  bool named = false;
  for (Slot& slot : slots) {
    if (slot.state.load(std::memory_order_acquire) != kReady) continue;
    if (address < slot.begin || address >= slot.end) continue;
    WriteText("geodex-server: SIGBUS reading ");
    WriteText(slot.path);
    WriteText(" at byte ");
    WriteNumber(address - slot.begin);
    WriteText(": the file shrank or was rewritten in place while mapped. Publish indexes by "
              "writing them elsewhere and renaming them into place (tests/README.md, \"Faults\"); the "
              "restarted server refuses the damaged file and serves the rest.\n");
    named = true;
    break;
  }
  if (!named) WriteText("geodex-server: SIGBUS outside every mapped index file\n");
  // Die of the signal itself, so that supervisors see what happened.
  ::signal(signal, SIG_DFL);
  ::raise(signal);
}

}  // namespace

MappedFileNotice::MappedFileNotice(std::span<const uint8_t> image, const std::string& path) {
  for (int i = 0; i < kMaxMappedFiles; ++i) {
    int expected = kFree;
    if (!slots[i].state.compare_exchange_strong(expected, kWriting, std::memory_order_acquire)) {
      continue;
    }
    Slot& slot = slots[i];
    slot.begin = reinterpret_cast<uintptr_t>(image.data());
    slot.end = slot.begin + image.size();
    const size_t n = std::min(path.size(), sizeof(slot.path) - 1);
    std::memcpy(slot.path, path.data(), n);
    slot.path[n] = '\0';
    slot.state.store(kReady, std::memory_order_release);
    slot_ = i;
    return;
  }
}

MappedFileNotice::~MappedFileNotice() {
  if (slot_ >= 0) slots[slot_].state.store(kFree, std::memory_order_release);
}

void InstallSigbusReport() {
  struct sigaction action = {};
  action.sa_sigaction = OnSigbus;
  action.sa_flags = SA_SIGINFO;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGBUS, &action, nullptr);
}

}  // namespace geodex::server
