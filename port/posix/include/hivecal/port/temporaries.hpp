// Temporaries that must not outlive a process ended by a signal (docs/cli.md "Outputs").
// An OutputSet registers each temporary file and folder while it exists; the handlers that
// remove_temporaries_on_signals() installs unlink them (files first, then folders) and end
// the process by the same signal, so the shell sees what ended it (exit 128 + N).
// The handler only reads a fixed table of atomic pointers and calls unlink/rmdir/raise:
// async-signal-safe. A command that handles a signal itself (record, simulate --serve)
// installs its own handler afterwards.
#pragma once

#include <string>

namespace hivecal::port {

/// Removes `path` (a file, or an empty folder when `is_folder`) if a signal ends the process
/// before unregister_temporary(path). More than the table holds (256) are not removed.
void register_temporary(const std::string& path, bool is_folder);
/// The temporary is gone or became an output: a signal leaves it alone.
void unregister_temporary(const std::string& path);

/// Installs the handlers for SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGUSR1, SIGUSR2, SIGALRM,
/// SIGVTALRM, SIGPROF and SIGXCPU, and ignores SIGXFSZ (a write beyond the file size limit
/// then fails with EFBIG, an output error).
void remove_temporaries_on_signals();

/// Blocks the signals remove_temporaries_on_signals() handles while alive (a set of outputs is moved into place
/// whole); a signal that came meanwhile is delivered on destruction.
class SignalsHeld {
 public:
  SignalsHeld();
  ~SignalsHeld();
  SignalsHeld(const SignalsHeld&) = delete;
  SignalsHeld& operator=(const SignalsHeld&) = delete;
};

}  // namespace hivecal::port
