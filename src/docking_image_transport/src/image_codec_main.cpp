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

}  // namespace

int main(int argc, char** argv) {
  dit::EncodeSettings settings;
  std::string out_dir;
  int repeat = 1;
  std::vector<std::string> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) != 0) {
      inputs.push_back(arg);
      continue;
    }
    if (i + 1 >= argc) return usage();
    const std::string value = argv[++i];
    try {
      if (arg == "--format") {
        if (!dit::parseCodec(value, &settings.codec)) return usage();
      } else if (arg == "--quality") settings.jpeg_quality = std::stoi(value);
      else if (arg == "--level") settings.png_level = std::stoi(value);
      else if (arg == "--repeat") repeat = std::max(1, std::stoi(value));
      else if (arg == "--out-dir") out_dir = value;
      else return usage();
    } catch (const std::exception&) {
      return usage();
    }
  }
  const std::vector<std::string> bad = dit::validateSettings(settings);
  if (!bad.empty()) {
    std::cerr << bad.front() << "\n";
    return 2;
  }
  if (out_dir.empty() || inputs.empty()) return usage();
  cv::setNumThreads(1);

  for (const std::string& path : inputs) {
    const cv::Mat in = cv::imread(path, cv::IMREAD_UNCHANGED);
    if (in.empty() || (in.type() != CV_8UC1 && in.type() != CV_8UC3)) {
      std::cerr << path << ": not an 8-bit grey or BGR image\n";
      return 1;
    }
    dit::ImageView view;
    view.width = in.cols;
    view.height = in.rows;
    view.encoding = in.channels() == 1 ? "mono8" : "bgr8";
    view.step = in.step;
    view.data = in.data;
    view.size = in.step * static_cast<std::size_t>(in.rows);
    std::vector<double> enc_ms, dec_ms;
    dit::EncodeResult encoded;
    dit::DecodeResult decoded;
    for (int k = 0; k < repeat; ++k) {
      const double t0 = cpuMs();
      encoded = dit::encode(view, settings);
      const double t1 = cpuMs();
      if (!encoded.ok()) {
        std::cerr << path << ": " << encoded.reason << "\n";
        return 1;
      }
      decoded = dit::decode(encoded.format, encoded.data.data(), encoded.data.size());
      const double t2 = cpuMs();
      if (!decoded.ok()) {
        std::cerr << path << ": " << decoded.reason << "\n";
        return 1;
      }
      enc_ms.push_back(t1 - t0);
      dec_ms.push_back(t2 - t1);
    }
    const cv::Mat out(decoded.image.height, decoded.image.width, in.type(), decoded.image.data.data(),
                      decoded.image.step);
    const std::string name = path.substr(path.find_last_of('/') + 1);
    if (!cv::imwrite(out_dir + "/" + name, out)) {
      std::cerr << "cannot write " << out_dir << "/" << name << "\n";
      return 1;
    }
    std::printf("{\"file\": \"%s\", \"encoding\": \"%s\", \"format\": \"%s\", \"bytes\": %zu, \"raw_bytes\": %zu, "
                "\"encode_ms\": %.3f, \"decode_ms\": %.3f}\n",
                name.c_str(), view.encoding.c_str(), encoded.format.c_str(), encoded.data.size(),
                static_cast<std::size_t>(in.cols) * in.rows * in.channels(), median(enc_ms), median(dec_ms));
  }
  return 0;
}
