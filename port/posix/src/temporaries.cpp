#include "hivecal/port/temporaries.hpp"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <cstring>

namespace hivecal::port {
namespace {

constexpr int kSlots = 256;
/// Each slot: a heap copy of the path (first byte 'F' file / 'D' folder, then the path), or
/// null. Written by the main thread only; read by the handler, which interrupts it.
std::atomic<char*> g_slots[kSlots];

/// Every signal whose default action ends the process and that a user, a shell or a job
/// system sends (kill -USR1, an alarm, a CPU limit, Ctrl-backslash), besides those that report a
/// fault of the process itself (SIGSEGV...). SIGPIPE is ignored by main() (writes fail with
/// EPIPE) and SIGXFSZ here (writes beyond `ulimit -f` fail with EFBIG): both become output
/// errors that the normal path reports, its temporaries removed.
constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM, SIGVTALRM, SIGPROF, SIGXCPU};

void remove_kind(char kind) {
  for (std::atomic<char*>& slot : g_slots) {
    const char* entry = slot.load();
    if (entry == nullptr || entry[0] != kind) continue;
    if (kind == 'F') {
      (void)::unlink(entry + 1);
    } else {
      (void)::rmdir(entry + 1);
    }
  }
}

void on_signal(int signal_number) {
  remove_kind('F');
  remove_kind('D');  // after their files: a folder is removed only when empty
  ::signal(signal_number, SIG_DFL);
  ::raise(signal_number);
}

sigset_t ending_signals() {
  sigset_t set;
  sigemptyset(&set);
  for (int s : kSignals) sigaddset(&set, s);
  return set;
}

}  // namespace

void register_temporary(const std::string& path, bool is_folder) {
  char* entry = static_cast<char*>(std::malloc(path.size() + 2));
  if (entry == nullptr) return;
  entry[0] = is_folder ? 'D' : 'F';
  std::memcpy(entry + 1, path.c_str(), path.size() + 1);
  for (std::atomic<char*>& slot : g_slots) {
    char* empty = nullptr;
    if (slot.compare_exchange_strong(empty, entry)) return;
  }
  std::free(entry);  // table full: this one is left behind by a signal
}

void unregister_temporary(const std::string& path) {
  for (std::atomic<char*>& slot : g_slots) {
    const char* entry = slot.load();
    if (entry == nullptr || path != entry + 1) continue;
    std::free(slot.exchange(nullptr));
    return;
  }
}

void remove_temporaries_on_signals() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  const sigset_t all = ending_signals();
  action.sa_mask = all;  // one handler at a time
  for (int s : kSignals) (void)::sigaction(s, &action, nullptr);
  (void)::signal(SIGXFSZ, SIG_IGN);
}

SignalsHeld::SignalsHeld() {
  const sigset_t set = ending_signals();
  (void)::sigprocmask(SIG_BLOCK, &set, nullptr);
}

SignalsHeld::~SignalsHeld() {
  const sigset_t set = ending_signals();
  (void)::sigprocmask(SIG_UNBLOCK, &set, nullptr);
}

}  // namespace hivecal::port
