#pragma once
// A second thread beside the soft-hand step (time_step.cpp), which hands it the work that it
// would otherwise do after its own: the cold PCG solve a failed warm start falls back to, and
// the line search's next halving. One job at a time, handed over without allocation or lock
// (an atomic state; the futex behind std::atomic::wait only while idle). The helper computes
// exactly what the step's thread would have, so the steps are the same to the bit.
#include <atomic>
#include <thread>

namespace haptic::softhand {

class HelperThread {
  public:
    using Job = void (*)(void* context);

    HelperThread();
    ~HelperThread();  // after the job under way, if any
    HelperThread(const HelperThread&) = delete;
    HelperThread& operator=(const HelperThread&) = delete;

    // Runs job(context) on the helper. Waits for the previous job first. Everything the job
    // reads or writes belongs to it until wait() returns.
    void start(Job job, void* context);
    // Returns once the job started last has returned (at once when there is none).
    void wait();
    // The job started last has returned, or there is none: wait() would not block.
    [[nodiscard]] bool done() const noexcept;

  private:
    enum State : int { kIdle, kQueued, kDone, kStop };
    void run();

    Job job_{nullptr};
    void* context_{nullptr};
    std::atomic<int> state_{kIdle};
    std::thread thread_;  // last: it starts once the members above exist
};

}  // namespace haptic::softhand
