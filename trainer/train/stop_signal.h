// Ctrl-C (SIGINT) and a scheduler's SIGTERM stop `ecrf train` at the end of its current step with
// a checkpoint, so that --resume continues the run exactly (run_events.cc StopIfAsked). The
// handlers only record the signal; a second signal ends the process at once (the checkpoint is
// written to a temporary file and renamed, so nothing half-written is left).
#ifndef ECRF_TRAINER_TRAIN_STOP_SIGNAL_H_
#define ECRF_TRAINER_TRAIN_STOP_SIGNAL_H_

namespace ecrf {
namespace trainer {

// While alive, SIGINT and SIGTERM are recorded (the first of each; the next ends the process as
// by default); the previous handlers come back when it goes. For the training loop only: the
// work after it (encoding, scoring) stops at Ctrl-C as any program does.
class StopSignalScope {
 public:
  StopSignalScope();
  ~StopSignalScope();
  StopSignalScope(const StopSignalScope&) = delete;
  StopSignalScope& operator=(const StopSignalScope&) = delete;
};

// The signal received since the scope began (0: none).
int StopSignal();

// "SIGINT" or "SIGTERM", the two signals the scope records.
const char* StopSignalName(int signal);

}  // namespace trainer
}  // namespace ecrf

#endif  // ECRF_TRAINER_TRAIN_STOP_SIGNAL_H_
