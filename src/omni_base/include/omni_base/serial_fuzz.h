// Seeded, deterministic stress of the motor protocol's stream decoder (ROS-free): shared by the
// `fuzz_serial_decoder` program (make fuzz-serial) and the gtests, so both check the same invariants.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace omni_base {
namespace serial_fuzz {

/// How often corrupting a zero-duty SET_DUTY frame produces a frame that would move a wheel.
struct CorruptionResult {
  std::uint64_t corrupted_frames{0};   ///< corrupted zero-duty frames fed (each followed by a clean one)
  std::uint64_t bit_flip_frames{0};    ///< of which corrupted by 1..4 bit flips
  std::uint64_t byte_replace_frames{0};///< of which corrupted by 1..4 random byte replacements
  std::uint64_t decoded_frames{0};     ///< frames the decoder returned in total
  std::uint64_t nonzero_duty{0};       ///< decoded SET_DUTY frames with a non-zero duty: accidental motion
  std::uint64_t clean_frames_lost{0};  ///< the clean zero-duty frame that followed was not decoded
};

/// Feeds `frames` corrupted copies of an all-zero SET_DUTY frame (3 wheels; half 1..4 bit flips, half
/// 1..4 random byte replacements, anywhere in the frame), each followed by an intact one.
CorruptionResult runCorruptionBenchmark(std::uint64_t frames, std::uint32_t seed);

/// Invariants checked on random streams: valid frames (random types, payloads, duties) embedded in
/// random garbage (with false start sequences), fed in random chunk sizes.
struct StreamFuzzResult {
  std::uint64_t inputs{0};             ///< streams fed
  std::uint64_t embedded_frames{0};    ///< valid frames placed in them
  std::uint64_t found_frames{0};       ///< of which decoded
  std::uint64_t extra_frames{0};       ///< frames decoded that were not placed (garbage with a matching CRC)
  std::vector<std::string> violations; ///< first few invariant violations, empty when all held
};

StreamFuzzResult runStreamFuzz(std::uint64_t inputs, std::uint32_t seed);

}  // namespace serial_fuzz
}  // namespace omni_base
