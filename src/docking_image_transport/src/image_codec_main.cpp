// image_codec: the `compressed` transport's codec on image files, for offline measurements.
//
//   image_codec --format jpeg|png [--quality Q] [--level L] [--repeat N] --out-dir DIR IN.png...
//
// Each input (1 channel: mono8, 3 channels: bgr8, as a camera publishes it) is encoded as the publisher
// plugin would, decoded as the subscriber plugin would, and the decoded image written to DIR/<name>
// (PNG, lossless). Prints one JSON object per file: bytes, format, CPU ms to encode and to decode
// (median of N repetitions, one thread).
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <string>
#include <vector>

#include "docking_image_transport/codec.h"

namespace dit = docking_image_transport;

namespace {

double cpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

int usage() {
  std::cerr << "usage: image_codec --format jpeg|png [--quality Q] [--level L] [--repeat N] --out-dir DIR IN.png...\n";
  return 2;
}

struct Arguments {
  dit::EncodeSettings settings;
  std::string out_dir;
  int repeat = 1;
  std::vector<std::string> inputs;
};

/// False on a malformed command line (then usage()).
bool parseArguments(int argc, char** argv, Arguments* a) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0) {
      a->inputs.push_back(arg);
      continue;
    }
    if (i + 1 >= argc) return false;
    const std::string value = argv[++i];
    try {
      if (arg == "--format") {
        if (!dit::parseCodec(value, &a->settings.codec)) return false;
      } else if (arg == "--quality") a->settings.jpeg_quality = std::stoi(value);
      else if (arg == "--level") a->settings.png_level = std::stoi(value);
      else if (arg == "--repeat") a->repeat = std::max(1, std::stoi(value));
      else if (arg == "--out-dir") a->out_dir = value;
      else return false;
    } catch (const std::exception&) {
      return false;
    }
  }
  return true;
}

/// The image as a camera would publish it: mono8 or bgr8.
dit::ImageView viewOf(const cv::Mat& in) {
  dit::ImageView view;
  view.width = in.cols;
  view.height = in.rows;
  view.encoding = in.channels() == 1 ? "mono8" : "bgr8";
  view.step = in.step;
  view.data = in.data;
  view.size = in.step * static_cast<std::size_t>(in.rows);
  return view;
}

/// Encodes and decodes `repeat` times (CPU ms of each in enc_ms, dec_ms); false (reported) on a failure.
bool roundTrip(const std::string& path, const dit::ImageView& view, const Arguments& a, dit::EncodeResult* encoded,
               dit::DecodeResult* decoded, std::vector<double>* enc_ms, std::vector<double>* dec_ms) {
  for (int k = 0; k < a.repeat; ++k) {
    const double t0 = cpuMs();
    *encoded = dit::encode(view, a.settings);
    const double t1 = cpuMs();
    if (!encoded->ok()) {
      std::cerr << path << ": " << encoded->reason << "\n";
      return false;
    }
    *decoded = dit::decode(encoded->format, encoded->data.data(), encoded->data.size());
    const double t2 = cpuMs();
    if (!decoded->ok()) {
      std::cerr << path << ": " << decoded->reason << "\n";
      return false;
    }
    enc_ms->push_back(t1 - t0);
    dec_ms->push_back(t2 - t1);
  }
  return true;
}

/// One input: round trip, the decoded image to out_dir, its JSON line. The exit code (0: done).
int processFile(const std::string& path, const Arguments& a) {
  const cv::Mat in = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (in.empty() || (in.type() != CV_8UC1 && in.type() != CV_8UC3)) {
    std::cerr << path << ": not an 8-bit grey or BGR image\n";
    return 1;
  }
  const dit::ImageView view = viewOf(in);
  std::vector<double> enc_ms, dec_ms;
  dit::EncodeResult encoded;
  dit::DecodeResult decoded;
  if (!roundTrip(path, view, a, &encoded, &decoded, &enc_ms, &dec_ms)) return 1;
  const cv::Mat out(decoded.image.height, decoded.image.width, in.type(), decoded.image.data.data(),
                    decoded.image.step);
  const std::string name = path.substr(path.find_last_of('/') + 1);
  if (!cv::imwrite(a.out_dir + "/" + name, out)) {
    std::cerr << "cannot write " << a.out_dir << "/" << name << "\n";
    return 1;
  }
  std::printf("{\"file\": \"%s\", \"encoding\": \"%s\", \"format\": \"%s\", \"bytes\": %zu, \"raw_bytes\": %zu, "
              "\"encode_ms\": %.3f, \"decode_ms\": %.3f}\n",
              name.c_str(), view.encoding.c_str(), encoded.format.c_str(), encoded.data.size(),
              static_cast<std::size_t>(in.cols) * in.rows * in.channels(), median(enc_ms), median(dec_ms));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Arguments a;
  if (!parseArguments(argc, argv, &a)) return usage();
  const std::vector<std::string> bad = dit::validateSettings(a.settings);
  if (!bad.empty()) {
    std::cerr << bad.front() << "\n";
    return 2;
  }
  if (a.out_dir.empty() || a.inputs.empty()) return usage();
  cv::setNumThreads(1);
  for (const std::string& path : a.inputs) {
    const int code = processFile(path, a);
    if (code != 0) return code;
  }
  return 0;
}
