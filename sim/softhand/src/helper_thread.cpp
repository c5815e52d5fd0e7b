#include "haptic/softhand/helper_thread.hpp"

#include <algorithm>
#include <chrono>

namespace haptic::softhand {

namespace {

// Jobs come in bursts within one step (a solve, then line-search points) and last tens to
// hundreds of microseconds. Handed over through the futex alone, the thimble scene's step p99
// did not improve at all on the 2-vCPU VM (1 046 against 1 036 us without the helper): the
// wake-ups ate the gain. So both sides poll this long before they sleep; between steps (5-10
// ms) the helper naps on its timer until shortly before the step it expects, and a step off
// that beat wakes it with an empty job as it begins (time_step.cpp). With the CPU latency
// request held (sim.yaml cpu_latency_us) a futex-only hand-over still cost the thimble scene's
// p99 about 0.3 ms, for 10-23 % of a core saved (docs/benchmarks.md, eighteenth session).
constexpr std::chrono::microseconds kPollBeforeSleep{200};
// Expecting a job (expectNextJobAt): the timer wakes the helper this long before it (the RT
// loop's wake-up p99 on the VM is under 0.1 ms), and it polls until this long after it.
constexpr std::chrono::microseconds kWakeAhead{300};
constexpr std::chrono::microseconds kLateJob{1000};
// Asleep until then, it looks this often: a job that comes early (a caller stepping back to
// back, as the benchmarks do) waits at most this long, or is taken back by the step.
constexpr std::chrono::microseconds kNap{200};

}  // namespace

HelperThread::HelperThread() : thread_([this] { run(); }) {}

HelperThread::~HelperThread() {
    (void)withdraw();
    state_.store(kStop);
    state_.notify_all();
    thread_.join();
}

void HelperThread::start(Job job, void* context) {
    (void)withdraw();
    job_ = job;
    context_ = context;
    state_.store(kQueued);  // publishes job_ and context_ (sequentially consistent)
    state_.notify_one();
}

bool HelperThread::done() const noexcept {
    const int state = state_.load();
    return state == kIdle || state == kDone;
}

void HelperThread::expectNextJobAt(std::chrono::steady_clock::time_point at) noexcept {
    next_job_.store(at.time_since_epoch().count());
}

void HelperThread::awaitChange(int from, bool until_expected_job) {
    using Clock = std::chrono::steady_clock;
    const auto changed = [&] { return state_.load() != from; };
    const auto pollUntil = [&](Clock::time_point until) {
        while (!changed()) {
            if (Clock::now() >= until) {
                return false;
            }
        }
        return true;
    };
    if (pollUntil(Clock::now() + kPollBeforeSleep)) {
        return;
    }
    // Idle, until the job expected: naps on the timer (which wakes this core at once) and
    // looks between them, then polls from shortly before it to shortly after it.
    while (until_expected_job) {
        const Clock::time_point expected{Clock::duration{next_job_.load()}};
        const auto now = Clock::now();
        if (now >= expected + kLateJob) {
            break;  // none came: the caller is not stepping at its rate
        }
        if (now >= expected - kWakeAhead) {
            if (pollUntil(expected + kLateJob)) {
                return;
            }
            break;
        }
        std::this_thread::sleep_for(std::min<Clock::duration>(kNap, expected - kWakeAhead - now));
        if (changed()) {
            return;
        }
    }
    if (!changed()) {
        state_.wait(from);
    }
}

void HelperThread::wait() {
    for (;;) {
        const int state = state_.load();
        if (state == kIdle) {
            return;
        }
        if (state == kDone) {
            state_.store(kIdle);
            return;
        }
        awaitChange(state, false);
    }
}

bool HelperThread::withdraw() {
    int expected = kQueued;
    if (state_.compare_exchange_strong(expected, kIdle)) {
        return true;
    }
    wait();
    return false;
}

void HelperThread::run() {
    // Waits for a change of the state it last saw: kIdle before a job, kDone after one until
    // the step collects it (wait() stores kIdle without a wake-up; the next start() wakes a
    // sleeping helper).
    int seen = kIdle;
    for (;;) {
        awaitChange(seen, true);
        const int state = state_.load();
        if (state == kStop) {
            return;
        }
        int expected = kQueued;
        if (state == kQueued && state_.compare_exchange_strong(expected, kRunning)) {
            if (job_ != nullptr) {  // the job of the start() whose kQueued the exchange took
                job_(context_);
                jobs_run_.fetch_add(1, std::memory_order_relaxed);  // before kDone publishes it
            }
            state_.store(kDone);
            state_.notify_all();
            seen = kDone;
            continue;
        }
        seen = state == kQueued ? expected : state;  // taken back meanwhile, or kIdle/kDone
        if (seen == kStop) {
            return;  // taken back and stopped between the load and the exchange
        }
    }
}

}  // namespace haptic::softhand
