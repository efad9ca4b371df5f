// fuzz_serial_decoder: deterministic, seeded stress of the motor protocol's stream decoder.
//   fuzz_serial_decoder [--inputs N] [--corruptions N] [--seed S]
// Part 1 feeds N random streams (valid frames in garbage with false starts, random chunking) and
// checks the invariants (no crash, every embedded frame found, no frame with a bad check value, duties
// in range). Part 2 corrupts N zero-duty SET_DUTY frames (1..4 bit flips / byte replacements) and
// counts those that decode to a non-zero duty. Exit status 1 when an invariant fails or a corrupted
// frame would move a wheel.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "omni_base/serial_fuzz.h"

namespace {

struct Options {
  std::uint64_t inputs{1000000};
  std::uint64_t corruptions{1000000};
  std::uint32_t seed{12};
};

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    const unsigned long long value = std::strtoull(argv[i + 1], nullptr, 10);
    if (key == "--inputs") o.inputs = value;
    else if (key == "--corruptions") o.corruptions = value;
    else if (key == "--seed") o.seed = static_cast<std::uint32_t>(value);
    else return false;
  }
  return argc % 2 == 1;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    std::fprintf(stderr, "usage: %s [--inputs N] [--corruptions N] [--seed S]\n", argv[0]);
    return 2;
  }
  using omni_base::serial_fuzz::runCorruptionBenchmark;
  using omni_base::serial_fuzz::runStreamFuzz;
  int status = 0;

  auto t0 = std::chrono::steady_clock::now();
  const auto fuzz = runStreamFuzz(o.inputs, o.seed);
  std::printf("stream fuzz: %llu inputs (seed %u), %llu valid frames embedded, %llu found, %llu extra, %.1f s\n",
              static_cast<unsigned long long>(fuzz.inputs), o.seed,
              static_cast<unsigned long long>(fuzz.embedded_frames), static_cast<unsigned long long>(fuzz.found_frames),
              static_cast<unsigned long long>(fuzz.extra_frames), secondsSince(t0));
  for (const auto& v : fuzz.violations) std::printf("  VIOLATION: %s\n", v.c_str());
  if (!fuzz.violations.empty()) status = 1;

  t0 = std::chrono::steady_clock::now();
  const auto c = runCorruptionBenchmark(o.corruptions, o.seed);
  std::printf("corruption: %llu zero-duty frames corrupted (%llu by 1..4 bit flips, %llu by 1..4 byte "
              "replacements): %llu decoded to a non-zero duty, %llu following clean frames lost, %.1f s\n",
              static_cast<unsigned long long>(c.corrupted_frames), static_cast<unsigned long long>(c.bit_flip_frames),
              static_cast<unsigned long long>(c.byte_replace_frames), static_cast<unsigned long long>(c.nonzero_duty),
              static_cast<unsigned long long>(c.clean_frames_lost), secondsSince(t0));
  if (c.nonzero_duty != 0 || c.clean_frames_lost != 0) status = 1;
  std::printf("%s\n", status == 0 ? "PASS" : "FAIL");
  return status;
}
