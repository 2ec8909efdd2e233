// springy: the one flag that stops long work (a run, the advisor's tries, a study, a survey).
//
// A signal handler (app/: SIGINT, SIGTERM, SIGHUP) or the Python module (a KeyboardInterrupt)
// sets it; every loop that can run for more than a moment polls it between steps and stops,
// leaving its caller to clean up (temporary files) and exit. A lock-free atomic, so setting it
// from a signal handler is async-signal-safe.
#pragma once

namespace springy {

// True once an interruption was requested.
bool interrupted();
// Sets the flag (the first request decides the signal reported); async-signal-safe.
void requestInterrupt(int signal);
// Clears it (the Python module, once a command it stopped has returned).
void clearInterrupt();
// The first signal requested (0 if none).
int interruptSignal();

}  // namespace springy
