// prf-ruckig's C ABI over the official Ruckig core (vendor/ruckig): compile-time degrees of
// freedom (7 for the arm, 3 for the platform), no exceptions (throw_error = false), no heap
// (with compile-time DoFs every Ruckig vector is a std::array; the only std::vectors, the
// intermediate waypoints and per-section limits of InputParameter, stay empty).
//
// The generator lives in storage the caller owns (prf_ruckig<N>_size / _align bytes): its
// members are arrays, doubles, enums, std::optional of those and empty std::vectors, so the
// caller may move it with memcpy (libstdc++'s empty vector is three null pointers).
#include <cstddef>
#include <cstdint>
#include <new>

#include <ruckig/ruckig.hpp>

namespace {

template <size_t N>
struct Generator {
    ruckig::Ruckig<N, ruckig::StandardVector, false> otg;
    ruckig::InputParameter<N> input;
    ruckig::OutputParameter<N> output;

    explicit Generator(double dt) : otg(dt) {}
};

// The caller's view of one cycle (identical layout to prf_ruckig::ffi::Io<N>).
template <size_t N>
struct Io {
    double current_position[N], current_velocity[N], current_acceleration[N];
    double target_position[N], target_velocity[N], target_acceleration[N];
    double max_velocity[N], max_acceleration[N], max_jerk[N];
    // 0 position, 1 velocity (ruckig::ControlInterface).
    uint8_t control_interface;
    // 0 time, 1 time if necessary, 2 phase, 3 none (ruckig::Synchronization).
    uint8_t synchronization;
    // Outputs of the cycle.
    uint8_t new_calculation;
    double new_position[N], new_velocity[N], new_acceleration[N];
    double duration;
};

template <size_t N>
void copy(const double (&from)[N], std::array<double, N>& to) {
    for (size_t i = 0; i < N; ++i) to[i] = from[i];
}

template <size_t N>
void copy(const std::array<double, N>& from, double (&to)[N]) {
    for (size_t i = 0; i < N; ++i) to[i] = from[i];
}

template <size_t N>
int update(void* storage, Io<N>* io) {
    auto& g = *static_cast<Generator<N>*>(storage);
    auto& in = g.input;
    copy(io->current_position, in.current_position);
    copy(io->current_velocity, in.current_velocity);
    copy(io->current_acceleration, in.current_acceleration);
    copy(io->target_position, in.target_position);
    copy(io->target_velocity, in.target_velocity);
    copy(io->target_acceleration, in.target_acceleration);
    copy(io->max_velocity, in.max_velocity);
    copy(io->max_acceleration, in.max_acceleration);
    copy(io->max_jerk, in.max_jerk);
    in.control_interface = static_cast<ruckig::ControlInterface>(io->control_interface);
    in.synchronization = static_cast<ruckig::Synchronization>(io->synchronization);
    const ruckig::Result result = g.otg.update(in, g.output);
    if (result == ruckig::Result::Working || result == ruckig::Result::Finished) {
        copy(g.output.new_position, io->new_position);
        copy(g.output.new_velocity, io->new_velocity);
        copy(g.output.new_acceleration, io->new_acceleration);
        io->new_calculation = g.output.new_calculation ? 1 : 0;
        io->duration = g.output.trajectory.get_duration();
    }
    return static_cast<int>(result);
}

}  // namespace

// The caller reserves PRF_RUCKIG_STORAGE_BYTES (prf_ruckig::storage), aligned to 16.
#define PRF_RUCKIG_DOFS(N)                                                                  \
    static_assert(sizeof(Generator<N>) <= PRF_RUCKIG_STORAGE_BYTES, "storage too small");    \
    static_assert(alignof(Generator<N>) <= 16, "storage under-aligned");                     \
    extern "C" size_t prf_ruckig##N##_size() { return sizeof(Generator<N>); }                \
    extern "C" size_t prf_ruckig##N##_io_size() { return sizeof(Io<N>); }                    \
    extern "C" void prf_ruckig##N##_init(void* storage, double dt) {                         \
        new (storage) Generator<N>(dt);                                                      \
    }                                                                                        \
    extern "C" void prf_ruckig##N##_drop(void* storage) {                                    \
        static_cast<Generator<N>*>(storage)->~Generator<N>();                                \
    }                                                                                        \
    extern "C" int prf_ruckig##N##_update(void* storage, Io<N>* io) { return update<N>(storage, io); }

PRF_RUCKIG_DOFS(3)
PRF_RUCKIG_DOFS(7)
