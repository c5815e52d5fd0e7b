#pragma once
// A second thread beside the soft-hand step (time_step.cpp), which hands it the work that it
// would otherwise do after its own: the cold PCG solve a failed warm start falls back to, and
// the line search's next halving. One job at a time, handed over without allocation or lock
// (an atomic state; the futex behind std::atomic::wait only after a poll). A job the helper
// has not begun can be taken back, and the step then does it itself, so a helper slow to wake
// costs a step at most the rest of a job it has begun (a cold solve told to stop ends within
// one PCG iteration). The helper computes exactly what the step's thread would have, so the
// steps are the same to the bit.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>

namespace haptic::softhand {

class HelperThread {
  public:
    using Job = void (*)(void* context);

    HelperThread();
    ~HelperThread();  // after the job under way, if any
    HelperThread(const HelperThread&) = delete;
    HelperThread& operator=(const HelperThread&) = delete;

    // Queues job(context) for the helper, after withdraw()ing the previous job. Everything the
    // job reads or writes belongs to it until wait() or withdraw() returns.
    void start(Job job, void* context);
    // Wakes the helper with nothing to do (a start() of no job), ahead of the jobs to come.
    void wake() { start(nullptr, nullptr); }
    // Jobs the helper thread has run itself: neither taken back nor a wake().
    [[nodiscard]] std::uint64_t jobsRun() const noexcept {
        return jobs_run_.load(std::memory_order_relaxed);
    }
    // Returns once the job queued last has run (at once when there is none).
    void wait();
    // Takes the job queued last back if the helper has not begun it (returns true: it will
    // never run), else waits for it (returns false: it ran). False when there is none.
    bool withdraw();
    // The job queued last has run, or there is none: wait() would not block.
    [[nodiscard]] bool done() const noexcept;
    // When the next job is likely to come (the next step of a periodic caller). An idle helper
    // naps on its own timer until shortly before it and polls from then on: woken through the
    // futex after a few milliseconds asleep, a VM's idle vCPU took 2.9 ms (p50) to run it,
    // longer than a whole step.
    void expectNextJobAt(std::chrono::steady_clock::time_point at) noexcept;

  private:
    enum State : int { kIdle, kQueued, kRunning, kDone, kStop };
    void run();
    // Returns once the state is not `from` any more: polls, then sleeps on the futex. The
    // helper, idle (until_expected_job), first naps on its timer until shortly before the job
    // expected, and polls around it.
    void awaitChange(int from, bool until_expected_job);

    Job job_{nullptr};
    void* context_{nullptr};
    std::atomic<int> state_{kIdle};
    std::atomic<std::uint64_t> jobs_run_{0};
    std::atomic<std::chrono::steady_clock::rep> next_job_{0};  // steady_clock ticks
    std::thread thread_;  // last: it starts once the members above exist
};

}  // namespace haptic::softhand
