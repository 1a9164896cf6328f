// A native stack on stderr when a process dies of a fault, so a rare crash (a node in a long
// soak, the gym core under PPO in CI) leaves more than "Segmentation fault" behind.
//
// InstallCrashReport() puts a handler on SIGSEGV, SIGBUS, SIGFPE, SIGILL and SIGABRT that writes
// one line naming the program, signal, fault address and thread, then the crashing thread's
// frames (glibc backtrace_symbols_fd: `lib.so(symbol+offset) [address]`; resolve an executable's
// own frames with `addr2line -Cfe EXE OFFSET`), then hands the signal on to the handler that was
// there before (Python's faulthandler, a core dump, the default action): the process still dies
// of the same signal, with the same exit status. Only async-signal-safe calls are made in the
// handler (backtrace() is warmed up at install, so it loads nothing then). Calling it again
// changes only the program name.
#pragma once

namespace unav::common {

/// `program` is copied (up to 63 characters) for the report's first line.
void InstallCrashReport(const char* program);

}  // namespace unav::common
