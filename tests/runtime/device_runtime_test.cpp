// The per-device tick of hapticd against the emulated devices (real drivers, renderers,
// safety stages and emulator models on a loopback bus, synthetic time).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "haptic/emu/device_models.hpp"
#include "haptic/kinesthetic/anisotropic.hpp"
#include "haptic/protocol/exoskeleton_protocol.hpp"
#include "haptic/protocol/thimble_protocol.hpp"
#include "haptic/runtime/exoskeleton_channel.hpp"
#include "haptic/runtime/thimble_channel.hpp"
#include "runtime_rig.hpp"

namespace haptic::testing {
namespace {

using ::testing::HasSubstr;

TEST(DeviceRuntime, DevicesComeOnlineAndRenderContactWhileRendering) {
    RuntimeRig rig;
    rig.offerContact();
    rig.ticks(20);
    const auto& exo = rig.core.deviceReport(kExo);
    EXPECT_EQ(exo.run_state, msgs::DeviceRunState::kReady);
    EXPECT_EQ(rig.core.deviceReport(kThimble).run_state, msgs::DeviceRunState::kReady);
    EXPECT_EQ(rig.exoForce(), 0.0) << "IDLE sends no force";
    EXPECT_LT(distance(rig.thimbleTargets(), retract(rig)), 1e-12) << "IDLE holds the retract pose";
    EXPECT_GT(exo.can.rx_frames, 20U);
    EXPECT_GT(exo.can.tx_frames, 10U);
    EXPECT_EQ(exo.can.bus_state, msgs::BusState::kErrorActive);
    // Measured state comes from the emulated device, not zeros.
    EXPECT_GT(std::abs(exo.joint_position_rad[0]) + std::abs(exo.joint_position_rad[1]), 0.1);
    EXPECT_GT(exo.actuator_position[0], 0.0);

    renderWithContact(rig);
    EXPECT_NEAR(std::abs(rig.exoForce()), 10.0, 1e-9) << "the wall saturates at safety.max_force_n";
    EXPECT_EQ(rig.core.deviceReport(kExo).run_state, msgs::DeviceRunState::kActive);
    EXPECT_GT(distance(rig.thimbleTargets(), retract(rig)), 0.05) << "the plate presses the pad";
    EXPECT_TRUE(rig.core.deviceReport(kExo).status_bits &
                static_cast<std::uint32_t>(msgs::DeviceStatusBit::kOnline));
    // The emulated actuator follows the command (first-order lag of 5 ms).
    EXPECT_NEAR(rig.core.deviceReport(kExo).actuator_force[0], rig.exoForce(), 0.5);
    EXPECT_EQ(rig.telemetry.device_index, kThimble);
    EXPECT_EQ(rig.core.deviceReport(kThimble).thimble.servo_angle_cmd_rad[0],
              rig.thimbleTargets()[0]);
}

TEST(DeviceRuntime, SwitchingAmongAllSixMethodsWhileRenderingNeverStepsTheForce) {
    RuntimeRig rig;
    // A wall across MCP and PIP that the sim moves with the finger (the emulated user flexes
    // on its own), a little inside it: the strategies ask for different forces below the clamp.
    auto place_wall = [&rig] {
        const auto& q = rig.core.deviceReport(kExo).joint_position_rad;
        msgs::LinearConstraint& wall = rig.constraint_set.constraints[0];
        wall.a = {-1.0, -0.5, 0.0};
        wall.b = -(q[0] + 0.5 * q[1]) + 0.03;
        rig.offerContact();
    };
    rig.ticks(20);
    place_wall();
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEnable));
    for (int i = 0; i < 300; ++i) {
        if (i % 10 == 0) {
            place_wall();
        }
        rig.tick();
    }
    const std::array<const char*, 6> methods{"standard", "naive",       "nullspace",
                                             "subspace", "anisotropic", "linearized_subspace"};
    const auto& exo = static_cast<runtime::ExoskeletonChannel&>(rig.runtime.channel(kExo));
    const double rate_step_n = 500.0 * 1e-3;  // safety.max_force_rate_n_per_s over one tick
    double previous_n = rig.exoForce();
    double largest_step_n = 0.0;
    double largest_passivity_cut_n = 0.0;
    int pushing_ticks = 0;
    int clamped_ticks = 0;
    int ticks = 0;
    for (int round = 0; round < 3; ++round) {
        for (const char* method : methods) {
            ASSERT_TRUE(rig.command(msgs::CommandKind::kSetMethod, method)) << method;
            for (int i = 0; i < 100; ++i, ++ticks) {
                if (i % 10 == 0) {
                    place_wall();
                }
                rig.tick();
                const double step_n = std::abs(rig.exoForce() - previous_n);
                // The passivity controller may cut a force towards zero at once when the
                // port's energy budget runs out (port_safety.hpp); that is not the switch's doing
                // and is counted apart. Every other change is bounded by the rate limit.
                const bool passivity_cut =
                    (exo.portFlags() & kinesthetic::kPortPassivityActive) != 0 &&
                    std::abs(rig.exoForce()) < std::abs(previous_n) &&
                    rig.exoForce() * previous_n >= 0.0;
                if (passivity_cut) {
                    largest_passivity_cut_n = std::max(largest_passivity_cut_n, step_n);
                } else {
                    largest_step_n = std::max(largest_step_n, step_n);
                }
                previous_n = rig.exoForce();
                pushing_ticks += std::abs(previous_n) > 0.5 ? 1 : 0;
                clamped_ticks += std::abs(previous_n) > 9.99 ? 1 : 0;
            }
            EXPECT_EQ(config::toString(exo.method()), std::string(method)) << "switched live";
            EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
        }
    }
    EXPECT_LE(largest_step_n, rate_step_n + 1e-9);
    std::printf("largest passivity cut %.3f N (not bounded by the rate limit)\n",
                largest_passivity_cut_n);
    EXPECT_GT(pushing_ticks, ticks / 2) << "the wall is felt while the methods change";
    EXPECT_LT(clamped_ticks, ticks / 10) << "below the clamp, where the methods differ";
}

// Each coupling key of the device file changes what the channel renders. The rigs stay IDLE
// (no force is sent), so the emulated finger moves the same in both and the renderer's outputs
// compare tick by tick; the wall sits 0.01 rad inside the finger, re-placed every 10 ticks.
// The relay's status comes on the exoskeleton's bus: a press read in a tick zeroes that tick's
// commands, and only release and an operator's clear and enable bring force back.
TEST(DeviceRuntime, AnEstopRelayPressZeroesTheForceInTheTickThatReadsIt) {
    RuntimeRig rig;
    rig.attachEstopRelay();
    renderWithContact(rig);
    ASSERT_GT(std::abs(rig.exoForce()), 1.0);
    std::string error;
    ASSERT_TRUE(rig.estop_relay->command("press", error));
    // The relay sends every 10 ms: tick until hapticd has read the press, then look at the
    // command that tick wrote.
    int ticks = 0;
    while (rig.core.state() == msgs::DaemonState::kRendering && ticks < 20) {
        rig.tick();
        ++ticks;
    }
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kEstop) << "after " << ticks << " ticks";
    EXPECT_LE(ticks, 10);
    EXPECT_EQ(rig.exoForce(), 0.0) << "the same tick";
    ASSERT_EQ(rig.core.stateMachine().faultCount(), 1U);
    EXPECT_EQ(rig.core.stateMachine().fault(0).code, daemon::kFaultEstopPressed);
    EXPECT_EQ(rig.runtime.estopRelay()->decoder().rejects().total(), 0U);

    rig.ticks(300);  // the thimble retracts at its servo rate limit
    EXPECT_LT(distance(rig.thimbleTargets(), retract(rig)), 1e-12);
    EXPECT_FALSE(rig.command(msgs::CommandKind::kClearFault)) << "still pressed";
    ASSERT_TRUE(rig.estop_relay->command("release", error));
    rig.ticks(15);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kEstop) << "a release re-arms nothing";
    ASSERT_TRUE(rig.command(msgs::CommandKind::kClearFault));
    renderWithContact(rig);
    // Rendering again (the force itself depends on where the emulated finger is by now).
    EXPECT_EQ(rig.core.outputGain(kExo), 1.0);
    EXPECT_EQ(rig.core.deviceReport(kExo).run_state, msgs::DeviceRunState::kActive);

    // A relay that falls silent is a pressed one, 30 ms after its last status.
    ASSERT_TRUE(rig.estop_relay->command("silence", error));
    ticks = 0;
    while (rig.core.state() == msgs::DaemonState::kRendering && ticks < 100) {
        rig.offerContact();
        rig.tick();
        ++ticks;
    }
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kEstop);
    EXPECT_GE(ticks, 21);
    EXPECT_LE(ticks, 32);
    EXPECT_EQ(rig.exoForce(), 0.0);
    EXPECT_EQ(rig.core.stateMachine().fault(0).code, daemon::kFaultEstopRelaySilent);
}

TEST(DeviceRuntime, EveryCouplingKeyOfTheDeviceFileChangesTheRendering) {
    auto rig_with = [](double k_a, double k_u, double b_v, double mass_kg,
                       config::RenderingMethod method) {
        return std::make_unique<RuntimeRig>([=](std::vector<config::DeviceConfig>& devices) {
            // The stiffness clamp off (it lowers k_a wherever the linkage makes the coupling
            // stiffer than safety.max_stiffness_n_per_m, and is tested on its own below), so
            // that each coupling key shows alone.
            devices[kExo].safety.max_stiffness_n_per_m = 1e12;
            auto& rendering = std::get<config::ExoskeletonConfig>(devices[kExo].params).rendering;
            rendering.tracking_stiffness_nm_per_rad = k_a;
            rendering.user_stiffness_nm_per_rad = k_u;
            rendering.actuator_damping_n_s_per_m = b_v;
            rendering.passivity_port_mass_kg = mass_kg;
            rendering.method = method;
        });
    };
    const auto linearized = config::RenderingMethod::kLinearizedSubspace;
    const auto anisotropic = config::RenderingMethod::kAnisotropic;
    auto base = rig_with(2.0, 0.6, 40.0, 0.1, linearized);
    auto stiffer = rig_with(4.0, 0.6, 40.0, 0.1, linearized);
    auto undamped = rig_with(2.0, 0.6, 0.0, 0.1, linearized);
    auto heavier = rig_with(2.0, 0.6, 40.0, 0.4, linearized);
    auto soft_user = rig_with(2.0, 0.6, 40.0, 0.1, anisotropic);
    auto stiff_user = rig_with(2.0, 6.0, 40.0, 0.1, anisotropic);
    // The channel follows the daemon's method (hapticd starts it from the device file; this
    // rig's core starts with linearized_subspace).
    ASSERT_TRUE(soft_user->command(msgs::CommandKind::kSetMethod, "anisotropic"));
    ASSERT_TRUE(stiff_user->command(msgs::CommandKind::kSetMethod, "anisotropic"));
    std::vector<RuntimeRig*> rigs{base.get(),    stiffer.get(),   undamped.get(),
                                  heavier.get(), soft_user.get(), stiff_user.get()};
    auto channel = [](RuntimeRig& rig) -> const runtime::ExoskeletonChannel& {
        return static_cast<runtime::ExoskeletonChannel&>(rig.runtime.channel(kExo));
    };
    int compared = 0;
    double damping_difference_n = 0.0;
    for (int i = 0; i < 400; ++i) {
        for (RuntimeRig* rig : rigs) {
            if (i % 10 == 0) {
                const auto& q = rig->core.deviceReport(kExo).joint_position_rad;
                msgs::LinearConstraint& wall = rig->constraint_set.constraints[0];
                wall.a = {-1.0, -0.5, 0.0};
                wall.b = -(q[0] + 0.5 * q[1]) + 0.01;
                rig->offerContact();
            }
            rig->tick();
        }
        const auto& out = channel(*base).renderOutput();
        if (i < 20 || !out.in_contact) {
            continue;
        }
        ++compared;
        // k_a: the coupling force doubles with it (same finger, same wall).
        EXPECT_NEAR(channel(*stiffer).renderOutput().coupling_force.norm(),
                    2.0 * out.coupling_force.norm(), 1e-9 * (1.0 + out.coupling_force.norm()));
        // b_v: only the damping part of the actuator force differs.
        damping_difference_n = std::max(
            damping_difference_n,
            std::abs(channel(*undamped).renderOutput().actuator_force[0] - out.actuator_force[0]));
        // k_u: anisotropic's closed-form rho* follows it.
        EXPECT_NEAR(channel(*soft_user).renderOutput().rho,
                    kinesthetic::optimalRhoIsotropic(2.0, 0.6), 1e-12);
        EXPECT_NEAR(channel(*stiff_user).renderOutput().rho,
                    kinesthetic::optimalRhoIsotropic(2.0, 6.0), 1e-12);
    }
    EXPECT_GT(compared, 100);
    EXPECT_GT(damping_difference_n, 0.01) << "the finger moves, so b_v must show";
    // The port mass bounds what the passivity controller lets through at rest: b = T^2 / m.
    // The channels' own controllers (copies, reset), fed the same motion and credit: a guard
    // that built its controller without the key would give the same limit in both.
    EXPECT_DOUBLE_EQ(channel(*heavier).portGuard().config().passivity_port_mass_kg, 0.4);
    kinesthetic::PassivityController light = channel(*base).portGuard().passivity();
    kinesthetic::PassivityController heavy = channel(*heavier).portGuard().passivity();
    for (auto* controller : {&light, &heavy}) {
        controller->reset();
        controller->setEnabled(true);
        controller->observe(0.01);
        controller->observe(0.01);
        controller->creditEnvironmentWork(1e-5);
    }
    EXPECT_NEAR(std::abs(heavy.limit(-10.0)), 2.0 * std::abs(light.limit(-10.0)), 1e-9);
}

// One tick of hapticd's way out (daemon_app.cpp, after the loop): the emulators run, the
// buses are drained, and every device gets its safe command instead of the rendered one.
void safeStopTick(RuntimeRig& rig) {
    rig.now += kMs;
    rig.host.setTime(rig.now);
    rig.target.setTime(rig.now);
    can::CanFrame frame;
    while (rig.target.read(frame) == can::IoResult::kOk) {
        for (auto& emulator : rig.emulators) {
            emulator->handleFrame(frame, rig.now);
        }
    }
    for (auto& emulator : rig.emulators) {
        emulator->tick(rig.now);
    }
    rig.runtime.read(rig.now);
    rig.runtime.writeSafe();
}

TEST(DeviceRuntime, WriteSafeDisablesTheExoskeletonAndRetractsTheThimbleWhileRendering) {
    RuntimeRig rig;
    renderWithContact(rig);
    ASSERT_NEAR(std::abs(rig.exoForce()), 10.0, 1e-9);
    ASSERT_GT(distance(rig.thimbleTargets(), retract(rig)), 0.05);
    const auto& exo = static_cast<runtime::ExoskeletonChannel&>(rig.runtime.channel(kExo));
    const auto& thimble = static_cast<runtime::ThimbleChannel&>(rig.runtime.channel(kThimble));
    ASSERT_NE(exo.driver().state().actuator.status & protocol::kExoEnabled, 0) << "rendering";
    const double rendered_n = exo.driver().state().actuator.force_n;
    ASSERT_GT(std::abs(rendered_n), 5.0) << "the emulated actuator pushes before the stop";

    for (int i = 0; i < 5; ++i) {
        safeStopTick(rig);
    }
    EXPECT_EQ(exo.command().force_n, 0.0);
    EXPECT_FALSE(exo.command().enable);
    EXPECT_LT(distance(thimble.command().servo_target_rad, retract(rig)), 1e-12);
    // The device's own state frames, not hapticd's view: the emulated actuator reports itself
    // disabled and its force decays with its 5 ms lag (5 ticks: to under half).
    EXPECT_EQ(exo.driver().state().actuator.status & protocol::kExoEnabled, 0);
    EXPECT_LT(std::abs(exo.driver().state().actuator.force_n), 0.5 * std::abs(rendered_n));
}

TEST(DeviceRuntime, StaleSimInputFadesToZeroWithinTheTimeoutAndNeverStepsUp) {
    RuntimeRig rig;
    renderWithContact(rig);
    double previous = std::abs(rig.exoForce());
    double previous_thimble = distance(rig.thimbleTargets(), retract(rig));
    ASSERT_GT(previous, 1.0);
    // The sim stops: its last message came 10 ticks ago (renderWithContact), so tick i sees an
    // input 11 + i ms old. At the 20 ms sim_timeout both devices are at zero / retracting, and
    // the fade (its last quarter) has not begun before 15 ms.
    for (int i = 0; i < 30; ++i) {
        rig.tick();
        const double force = std::abs(rig.exoForce());
        const double thimble = distance(rig.thimbleTargets(), retract(rig));
        EXPECT_LE(force, previous + 1e-12) << "tick " << i;
        EXPECT_LE(thimble, previous_thimble + 1e-12) << "tick " << i;
        previous = force;
        previous_thimble = thimble;
        if (i >= 9) {
            EXPECT_EQ(force, 0.0) << "tick " << i;
        }
        if (i <= 3) {
            EXPECT_GT(force, 1.0) << "tick " << i << ": faded before three quarters of the timeout";
        }
    }
    EXPECT_EQ(rig.core.deviceReport(kExo).run_state, msgs::DeviceRunState::kSafe);
    // Fresh input ramps back up, never a step (100 ms fade-in, rate limit).
    for (int i = 0; i < 50; ++i) {
        rig.offerContact();
        rig.tick();
        const double force = std::abs(rig.exoForce());
        EXPECT_LE(force - previous, 0.5 + 1e-9) << "tick " << i;  // 500 N/s at 1 kHz
        previous = force;
    }
    EXPECT_GT(previous, 1.0);
}

TEST(DeviceRuntime, HeartbeatLossRaisesALatchedFaultNamingTheDevice) {
    RuntimeRig rig;
    renderWithContact(rig);
    rig.emulatorFault(kThimble, "heartbeat stop");
    rig.ticks(70);  // heartbeat_timeout_ms 50 (+ up to one 10 ms heartbeat period)
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    ASSERT_EQ(rig.core.stateMachine().faultCount(), 1U);
    const auto& fault = rig.core.stateMachine().fault(0);
    EXPECT_EQ(fault.code, runtime::kFaultHeartbeatLost);
    EXPECT_EQ(fault.device_id.view(), "thimble");
    EXPECT_THAT(std::string(fault.message.view()), HasSubstr("heartbeat lost"));
    EXPECT_EQ(rig.core.deviceReport(kThimble).run_state, msgs::DeviceRunState::kFault);
    EXPECT_EQ(rig.exoForce(), 0.0) << "FAULT holds every device at zero";
    // The thimble's safe state is the retract pose, reached at servos.max_rate_deg_per_s.
    double previous = distance(rig.thimbleTargets(), retract(rig));
    for (int i = 0; i < 300; ++i) {
        rig.tick();
        const double now = distance(rig.thimbleTargets(), retract(rig));
        ASSERT_LE(now, previous + 1e-12) << "tick " << i;
        previous = now;
    }
    EXPECT_LT(previous, 1e-12);

    // Latched: the heartbeat returns, the fault stays until clear; clear lands in IDLE.
    rig.emulatorFault(kThimble, "heartbeat start");
    rig.ticks(30);
    EXPECT_EQ(rig.core.deviceReport(kThimble).run_state, msgs::DeviceRunState::kFault);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 1U) << "raised once, not once per tick";
    ASSERT_TRUE(rig.command(msgs::CommandKind::kClearFault));
    rig.ticks(5);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kIdle);
    EXPECT_EQ(rig.core.deviceReport(kThimble).run_state, msgs::DeviceRunState::kReady);
}

// A clear while the cause stands is refused with what stands (it would only come back a tick
// later, after a reply saying IDLE); once the cause has gone, the same clear is taken.
TEST(DeviceRuntime, ClearWhileTheCauseRemainsIsRefusedAndSaysWhatStands) {
    RuntimeRig rig;
    renderWithContact(rig);
    rig.emulatorFault(kExo, "heartbeat stop");
    rig.ticks(70);
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    EXPECT_FALSE(rig.command(msgs::CommandKind::kClearFault));
    EXPECT_EQ(std::string(rig.reply.message.view()),
              "device 'exo' still shows the cause of fault 100; clear once it has gone "
              "(hapticctl status)");
    rig.ticks(2);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    EXPECT_EQ(rig.core.stateMachine().fault(0).device_id.view(), "exo");
    rig.emulatorFault(kExo, "heartbeat start");
    rig.ticks(30);
    EXPECT_TRUE(rig.command(msgs::CommandKind::kClearFault)) << rig.reply.message.view();
    rig.ticks(5);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kIdle);
}

TEST(DeviceRuntime, BusOffFaultsTheDevicesOnThatBus) {
    RuntimeRig rig;
    renderWithContact(rig);
    rig.emulatorFault(kExo, "busoff");
    rig.ticks(3);
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    EXPECT_EQ(rig.core.stateMachine().fault(0).code, runtime::kFaultBusOff);
    EXPECT_EQ(rig.core.deviceReport(kExo).can.bus_state, msgs::BusState::kBusOff);
    EXPECT_EQ(rig.core.deviceReport(kExo).run_state, msgs::DeviceRunState::kFault);
    EXPECT_EQ(rig.exoForce(), 0.0);
    // Both devices share the loopback bus here, so both are named.
    ASSERT_EQ(rig.core.stateMachine().faultCount(), 2U);
    EXPECT_EQ(rig.core.stateMachine().fault(1).device_id.view(), "thimble");
}

TEST(DeviceRuntime, DeviceFaultReportIsRaisedWithItsCode) {
    RuntimeRig rig;
    renderWithContact(rig);
    rig.emulatorFault(kExo, "fault 2");
    rig.ticks(20);
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    EXPECT_EQ(rig.core.stateMachine().fault(0).code, runtime::kFaultDeviceReported);
    EXPECT_THAT(std::string(rig.core.stateMachine().fault(0).message.view()),
                HasSubstr("overtemperature"));
}

// hapticd stalls (SIGSTOP, a starved VM) while rendering: the devices' own command timeout
// makes them safe without it, and when it wakes it latches its own stall instead of resuming.
TEST(DeviceRuntime, AStalledDaemonIsCaughtByTheDevicesOwnTimeoutAndLatchesAFault) {
    RuntimeRig rig;
    renderWithContact(rig);
    ASSERT_GT(std::abs(rig.emulators[kExo]->exoskeletonModel()->forceN()), 5.0);
    rig.devicesOnly(rig.devices[kExo].can.command_timeout_ms + 2);
    EXPECT_TRUE(rig.emulators[kExo]->commandTimedOut());
    EXPECT_TRUE(rig.emulators[kThimble]->commandTimedOut());
    EXPECT_EQ(rig.emulators[kExo]->exoskeletonModel()->forceN(), 0.0) << "limp by itself";
    for (int i = 0; i < 20; ++i) {
        rig.offerContact();
        rig.tick();
        ASSERT_EQ(rig.emulators[kExo]->exoskeletonModel()->forceN(), 0.0) << "tick " << i;
    }
    // The stall is hapticd's own fault; the devices' timeout is its consequence, not theirs.
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    ASSERT_EQ(rig.core.stateMachine().faultCount(), 1U);
    EXPECT_EQ(rig.core.stateMachine().fault(0).code, daemon::kFaultLoopStalled);
    EXPECT_EQ(rig.core.stateMachine().fault(0).device_id.view(), "hapticd");
    EXPECT_THAT(std::string(rig.core.stateMachine().fault(0).message.view()),
                HasSubstr("loop stalled 13.0 ms (limit 10.0 ms)"));
    // FAULT sends the safe command, which acknowledges the devices' timeout: at once for the
    // exoskeleton (disable), for the thimble once hapticd's servo limiter has walked its
    // targets back to the retract pose. The daemon stays latched until an operator clears it,
    // and force needs a new enable.
    EXPECT_FALSE(rig.emulators[kExo]->commandTimedOut());
    rig.ticks(500);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    EXPECT_FALSE(rig.emulators[kThimble]->commandTimedOut());
    ASSERT_TRUE(rig.command(msgs::CommandKind::kClearFault));
    rig.ticks(20);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kIdle);
    EXPECT_EQ(rig.exoForce(), 0.0);
    renderWithContact(rig);
    // Re-enabled, the port starts a new passivity interval with no stored energy: the wall
    // pushes again once the user's finger moves into it (the emulated user flexes at 0.5 Hz).
    double largest_n = 0.0;
    for (int i = 0; i < 3000; ++i) {
        if (i % 10 == 0) {
            rig.offerContact();
        }
        rig.tick();
        largest_n = std::max(largest_n, std::abs(rig.exoForce()));
    }
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
    EXPECT_NEAR(largest_n, 10.0, 1e-9);
}

// A hapticd restarted after a crash finds the devices timed out by its predecessor's silence:
// already safe, so its first safe commands acknowledge them and it comes up IDLE.
TEST(DeviceRuntime, ACommandTimeoutLeftByThePreviousHostIsAcknowledgedAtStart) {
    RuntimeRig rig;
    protocol::ExoskeletonCodec exo_codec(rig.devices[kExo]);
    protocol::ThimbleCodec thimble_codec(rig.devices[kThimble]);
    can::CanFrame frame;
    ASSERT_TRUE(exo_codec.encodeCommand({6.0, true}, frame));
    ASSERT_EQ(rig.host.write(frame), can::IoResult::kOk);
    ASSERT_TRUE(thimble_codec.encodeCommand({{0.9, 0.9, 0.9}}, frame));
    ASSERT_EQ(rig.host.write(frame), can::IoResult::kOk);
    rig.devicesOnly(100);  // the previous host died after that command
    ASSERT_TRUE(rig.emulators[kExo]->commandTimedOut());
    ASSERT_TRUE(rig.emulators[kThimble]->commandTimedOut());
    rig.core.markStarted(rig.now);  // this hapticd's loop starts now
    rig.ticks(100);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kIdle);
    EXPECT_EQ(rig.core.stateMachine().faultCount(), 0U);
    EXPECT_FALSE(rig.emulators[kExo]->commandTimedOut());
    EXPECT_FALSE(rig.emulators[kThimble]->commandTimedOut());
    renderWithContact(rig);
    EXPECT_NEAR(std::abs(rig.exoForce()), 10.0, 1e-9);
}

TEST(DeviceRuntime, TransmitFailureForTenTicksFaults) {
    RuntimeRig rig;
    renderWithContact(rig);
    rig.host.injectBackpressure(9);
    rig.ticks(6);  // 9 writes (two devices per tick) refused: not yet a fault
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kRendering);
    rig.host.injectBackpressure(40);
    rig.ticks(25);
    ASSERT_EQ(rig.core.state(), msgs::DaemonState::kFault);
    // The devices, receiving nothing for as long, report their own command timeout too
    // (fault 4 as 102); the daemon's transmit fault must be among the listed causes.
    bool transmit_fault = false;
    for (std::size_t i = 0; i < rig.core.stateMachine().faultCount(); ++i) {
        transmit_fault = transmit_fault ||
                         rig.core.stateMachine().fault(i).code == runtime::kFaultTransmitFailed;
    }
    EXPECT_TRUE(transmit_fault);
}

TEST(DeviceRuntime, MethodCommandSwitchesTheKinestheticStrategy) {
    RuntimeRig rig;
    rig.ticks(5);
    auto& exo = static_cast<runtime::ExoskeletonChannel&>(rig.runtime.channel(kExo));
    EXPECT_EQ(exo.method(), config::RenderingMethod::kLinearizedSubspace);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kSetMethod, "anisotropic"));
    rig.tick();
    EXPECT_EQ(exo.method(), config::RenderingMethod::kAnisotropic);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kSetMethod, "naive"));
    rig.tick();
    EXPECT_EQ(exo.method(), config::RenderingMethod::kNaive);
}

TEST(DeviceRuntime, EstopZeroesForceAndClearReturnsToIdle) {
    RuntimeRig rig;
    renderWithContact(rig);
    ASSERT_TRUE(rig.command(msgs::CommandKind::kEstop));
    rig.tick();
    EXPECT_EQ(rig.exoForce(), 0.0);
    EXPECT_EQ(rig.core.deviceReport(kExo).status_bits &
                  static_cast<std::uint32_t>(msgs::DeviceStatusBit::kSafeState),
              static_cast<std::uint32_t>(msgs::DeviceStatusBit::kSafeState));
    ASSERT_TRUE(rig.command(msgs::CommandKind::kClearFault));
    rig.tick();
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kIdle);
}

TEST(DeviceRuntime, NeverHeardDevicesAreOfflineNotFaulted) {
    RuntimeRig rig;
    rig.emulatorFault(kExo, "heartbeat stop");
    rig.ticks(200);
    EXPECT_EQ(rig.core.deviceReport(kExo).run_state, msgs::DeviceRunState::kOffline);
    EXPECT_EQ(rig.core.state(), msgs::DaemonState::kIdle);
}

}  // namespace
}  // namespace haptic::testing
