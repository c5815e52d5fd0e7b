#include "haptic/softhand/helper_thread.hpp"

#include <chrono>

namespace haptic::softhand {

namespace {

// Jobs come in bursts within one step (a solve, then line-search points) and last tens to
// hundreds of microseconds. Handed over through the futex alone, the thimble scene's step p99
// did not improve at all on the 2-vCPU VM (1 046 against 1 036 us without the helper): the
// wake-ups ate the gain. So both sides poll this long before they sleep; between steps (5-10
// ms) the helper sleeps.
constexpr std::chrono::microseconds kPollBeforeSleep{200};

template <typename Predicate>
bool pollFor(std::chrono::microseconds span, Predicate ready) {
    const auto until = std::chrono::steady_clock::now() + span;
    do {
        if (ready()) {
            return true;
        }
    } while (std::chrono::steady_clock::now() < until);
    return ready();
}

}  // namespace

HelperThread::HelperThread() : thread_([this] { run(); }) {}

HelperThread::~HelperThread() {
    wait();
    state_.store(kStop);
    state_.notify_all();
    thread_.join();
}

void HelperThread::start(Job job, void* context) {
    wait();
    job_ = job;
    context_ = context;
    state_.store(kQueued);  // publishes job_ and context_ (sequentially consistent)
    state_.notify_one();
}

bool HelperThread::done() const noexcept {
    const int state = state_.load();
    return state == kIdle || state == kDone;
}

void HelperThread::wait() {
    if (state_.load() == kIdle) {
        return;
    }
    if (!pollFor(kPollBeforeSleep, [this] { return state_.load() == kDone; })) {
        for (int state = state_.load(); state != kDone; state = state_.load()) {
            state_.wait(state);
        }
    }
    state_.store(kIdle);
}

void HelperThread::run() {
    // Polls for a change of the state it last saw, then sleeps on it: kIdle before a job,
    // kDone after one until the step collects it (wait() stores kIdle without a wake-up; the
    // next start() wakes a sleeping helper).
    int seen = kIdle;
    for (;;) {
        if (!pollFor(kPollBeforeSleep, [&] { return state_.load() != seen; })) {
            state_.wait(seen);
        }
        const int state = state_.load();
        if (state == kStop) {
            return;
        }
        if (state == kQueued) {
            job_(context_);
            state_.store(kDone);
            state_.notify_all();
        }
        seen = state == kQueued ? static_cast<int>(kDone) : state;
    }
}

}  // namespace haptic::softhand
