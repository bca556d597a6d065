#include "trainer/train/stop_signal.h"

#include <signal.h>

namespace ecrf {
namespace trainer {
namespace {

volatile sig_atomic_t g_stop_signal = 0;
struct sigaction g_previous[2];
constexpr int kSignals[2] = {SIGINT, SIGTERM};

void RecordStopSignal(int signal) { g_stop_signal = signal; }

}  // namespace

StopSignalScope::StopSignalScope() {
  g_stop_signal = 0;
  struct sigaction action = {};
  action.sa_handler = RecordStopSignal;
  sigemptyset(&action.sa_mask);
  // SA_RESETHAND: the handler runs once; a second Ctrl-C is the default action, an exit.
  action.sa_flags = SA_RESETHAND;
  for (int k = 0; k < 2; ++k) sigaction(kSignals[k], &action, &g_previous[k]);
}

StopSignalScope::~StopSignalScope() {
  for (int k = 0; k < 2; ++k) sigaction(kSignals[k], &g_previous[k], nullptr);
}

int StopSignal() { return g_stop_signal; }

const char* StopSignalName(int signal) { return signal == SIGINT ? "SIGINT" : "SIGTERM"; }

}  // namespace trainer
}  // namespace ecrf
