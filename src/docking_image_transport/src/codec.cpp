#include "docking_image_transport/codec.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <climits>
#include <cstring>
#include <exception>

namespace docking_image_transport {
namespace {

// What an encoding looks like in memory; channels == 0: not supported.
struct Layout {
  int channels = 0;
  int depth_bytes = 0;
  bool colour = false;
  bool swap_rb = false;  // stored RGB, OpenCV's codecs want BGR
};

Layout layoutOf(const std::string& encoding) {
  if (encoding == "mono8") return {1, 1, false, false};
  if (encoding == "bgr8") return {3, 1, true, false};
  if (encoding == "rgb8") return {3, 1, true, true};
  if (encoding == "mono16") return {1, 2, false, false};
  return {};
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

// A complete stream starts with the codec's signature and ends with its end marker. libjpeg decodes a
// truncated JPEG without failing (it pads the missing rows with grey and only warns), so truncation must
// be caught here, before decoding.
bool looksComplete(Codec codec, const std::uint8_t* data, std::size_t size, std::string* reason) {
  if (codec == Codec::kJpeg) {
    if (size < 4 || data[0] != 0xFF || data[1] != 0xD8 || data[2] != 0xFF) {
      *reason = "not a JPEG stream (no SOI marker)";
      return false;
    }
    std::size_t end = size;
    while (end > 2 && data[end - 1] == 0x00) --end;  // some writers pad; ours does not
    if (data[end - 2] != 0xFF || data[end - 1] != 0xD9) {
      *reason = "JPEG stream truncated (no EOI marker at the end)";
      return false;
    }
    return true;
  }
  static const std::uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A};
  if (size < 8 + 12 || std::memcmp(data, kPngSignature, 8) != 0) {
    *reason = "not a PNG stream (no PNG signature)";
    return false;
  }
  if (std::memcmp(data + size - 8, "IEND", 4) != 0) {
    *reason = "PNG stream truncated (no IEND chunk at the end)";
    return false;
  }
  return true;
}

EncodeResult encodeFailure(EncodeError error, std::string reason) {
  EncodeResult r;
  r.error = error;
  r.reason = std::move(reason);
  return r;
}

DecodeResult decodeFailure(DecodeError error, std::string reason) {
  DecodeResult r;
  r.error = error;
  r.reason = std::move(reason);
  return r;
}

}  // namespace

bool parseCodec(const std::string& name, Codec* codec) {
  if (name == "jpeg") {
    *codec = Codec::kJpeg;
    return true;
  }
  if (name == "png") {
    *codec = Codec::kPng;
    return true;
  }
  return false;
}

const char* codecName(Codec codec) { return codec == Codec::kJpeg ? "jpeg" : "png"; }

std::vector<std::string> validateSettings(const EncodeSettings& s) {
  std::vector<std::string> reasons;
  if (s.codec != Codec::kJpeg && s.codec != Codec::kPng) reasons.push_back("format must be jpeg or png");
  if (s.jpeg_quality < 1 || s.jpeg_quality > 100)
    reasons.push_back("jpeg_quality must be in 1..100 (got " + std::to_string(s.jpeg_quality) + ")");
  if (s.png_level < 0 || s.png_level > 9)
    reasons.push_back("png_level must be in 0..9 (got " + std::to_string(s.png_level) + ")");
  return reasons;
}

const char* errorName(EncodeError error) {
  switch (error) {
    case EncodeError::kNone: return "none";
    case EncodeError::kBadSettings: return "bad_settings";
    case EncodeError::kUnsupportedEncoding: return "unsupported_encoding";
    case EncodeError::kWrongSize: return "wrong_size";
    case EncodeError::kEncoderFailed: return "encoder_failed";
  }
  return "unknown";
}

const char* errorName(DecodeError error) {
  switch (error) {
    case DecodeError::kNone: return "none";
    case DecodeError::kEmpty: return "empty";
    case DecodeError::kBadFormat: return "bad_format";
    case DecodeError::kUnsupportedEncoding: return "unsupported_encoding";
    case DecodeError::kCorrupt: return "corrupt";
    case DecodeError::kShapeMismatch: return "shape_mismatch";
  }
  return "unknown";
}

EncodeResult encode(const ImageView& image, const EncodeSettings& settings) {
  const std::vector<std::string> bad = validateSettings(settings);
  if (!bad.empty()) return encodeFailure(EncodeError::kBadSettings, bad.front());
  const Layout layout = layoutOf(image.encoding);
  if (layout.channels == 0)
    return encodeFailure(EncodeError::kUnsupportedEncoding,
                         "encoding '" + image.encoding + "' is not supported (mono8, bgr8, rgb8, mono16)");
  if (settings.codec == Codec::kJpeg && layout.depth_bytes != 1)
    return encodeFailure(EncodeError::kUnsupportedEncoding,
                         "encoding '" + image.encoding + "' has 16-bit pixels: JPEG is 8-bit, use png");
  if (image.width <= 0 || image.height <= 0)
    return encodeFailure(EncodeError::kWrongSize, "image is " + std::to_string(image.width) + "x" +
                                                      std::to_string(image.height));
  const std::size_t row_bytes = static_cast<std::size_t>(image.width) * layout.channels * layout.depth_bytes;
  if (image.step < row_bytes)
    return encodeFailure(EncodeError::kWrongSize, "step " + std::to_string(image.step) + " < " +
                                                      std::to_string(row_bytes) + " bytes of a " +
                                                      image.encoding + " row of width " +
                                                      std::to_string(image.width));
  const std::size_t needed = image.step * static_cast<std::size_t>(image.height);
  if (image.data == nullptr || image.size < needed)
    return encodeFailure(EncodeError::kWrongSize, "data has " + std::to_string(image.size) + " bytes, step x height = " +
                                                      std::to_string(needed));

  const int type = CV_MAKETYPE(layout.depth_bytes == 1 ? CV_8U : CV_16U, layout.channels);
  // cv::Mat needs a non-const pointer; nothing below writes through `view`.
  const cv::Mat view(image.height, image.width, type, const_cast<std::uint8_t*>(image.data), image.step);
  EncodeResult result;
  try {
    // A new Mat for converted data: converting into a header of `view` would write into the caller's image.
    cv::Mat input;
    if (layout.swap_rb) {
      cv::cvtColor(view, input, cv::COLOR_RGB2BGR);
    } else if (layout.depth_bytes == 2 && image.is_bigendian) {
      // The codecs read host-order (little-endian) 16-bit samples.
      input = view.clone();
      for (int r = 0; r < input.rows; ++r) {
        std::uint8_t* p = input.ptr<std::uint8_t>(r);
        for (int c = 0; c < input.cols; ++c) std::swap(p[2 * c], p[2 * c + 1]);
      }
    } else {
      input = view;
    }
    std::vector<int> params;
    if (settings.codec == Codec::kJpeg) params = {cv::IMWRITE_JPEG_QUALITY, settings.jpeg_quality};
    else params = {cv::IMWRITE_PNG_COMPRESSION, settings.png_level};
    if (!cv::imencode(settings.codec == Codec::kJpeg ? ".jpg" : ".png", input, result.data, params))
      return encodeFailure(EncodeError::kEncoderFailed, "cv::imencode failed");
  } catch (const std::exception& e) {
    return encodeFailure(EncodeError::kEncoderFailed, std::string("cv::imencode: ") + e.what());
  }
  result.format = image.encoding + "; " + codecName(settings.codec) + " compressed " + (layout.colour ? "bgr8" : "");
  return result;
}

namespace {

// decode's steps: each returns a failed DecodeResult, or an ok one to go on.

/// "<encoding>; <jpeg|png> compressed [target]", or the old bare "jpeg" / "png" (encoding then follows
/// from the decoded channels): the encoding (may be empty), the codec and its layout.
DecodeResult parseFormat(const std::string& format, std::string* encoding, std::string* scheme, Codec* codec,
                         Layout* layout) {
  const auto semicolon = format.find(';');
  if (semicolon == std::string::npos) {
    *scheme = trim(format);
  } else {
    *encoding = trim(format.substr(0, semicolon));
    const std::string rest = trim(format.substr(semicolon + 1));
    if (startsWith(rest, "compressedDepth"))
      return decodeFailure(DecodeError::kUnsupportedEncoding, "compressedDepth images are not supported");
    if (startsWith(rest, "jpeg compressed")) *scheme = "jpeg";
    else if (startsWith(rest, "png compressed")) *scheme = "png";
    else return decodeFailure(DecodeError::kBadFormat, "format '" + format + "' is not '<encoding>; jpeg|png compressed ...'");
  }
  if (!parseCodec(*scheme, codec))
    return decodeFailure(DecodeError::kBadFormat, "format '" + format + "' names no jpeg or png stream");
  if (!encoding->empty()) {
    *layout = layoutOf(*encoding);
    if (layout->channels == 0)
      return decodeFailure(DecodeError::kUnsupportedEncoding,
                           "encoding '" + *encoding + "' is not supported (mono8, bgr8, rgb8, mono16)");
  }
  return {};
}

/// The complete stream through cv::imdecode.
DecodeResult decodeStream(Codec codec, const std::string& scheme, const std::uint8_t* data, std::size_t size,
                          cv::Mat* decoded) {
  std::string reason;
  if (!looksComplete(codec, data, size, &reason)) return decodeFailure(DecodeError::kCorrupt, reason);
  try {
    const cv::Mat buffer(1, static_cast<int>(size), CV_8UC1, const_cast<std::uint8_t*>(data));
    *decoded = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const std::exception& e) {
    return decodeFailure(DecodeError::kCorrupt, std::string("cv::imdecode: ") + e.what());
  } catch (...) {
    return decodeFailure(DecodeError::kCorrupt, "cv::imdecode failed");
  }
  if (decoded->empty()) return decodeFailure(DecodeError::kCorrupt, std::string(scheme) + " stream does not decode");
  return {};
}

/// The decoded image against the encoding: named by the format, or (bare format) from its channels.
DecodeResult checkDecodedShape(const cv::Mat& decoded, std::string* encoding, Layout* layout) {
  if (encoding->empty()) {
    if (decoded.type() == CV_8UC1) *encoding = "mono8";
    else if (decoded.type() == CV_8UC3) *encoding = "bgr8";
    else if (decoded.type() == CV_16UC1) *encoding = "mono16";
    else return decodeFailure(DecodeError::kUnsupportedEncoding, "decoded image has " +
                                  std::to_string(decoded.channels()) + " channels of " +
                                  std::to_string(decoded.elemSize1() * 8) + " bits");
    *layout = layoutOf(*encoding);
  }
  const int expected = CV_MAKETYPE(layout->depth_bytes == 1 ? CV_8U : CV_16U, layout->channels);
  if (decoded.type() != expected)
    return decodeFailure(DecodeError::kShapeMismatch,
                         "format says " + *encoding + " but the stream decodes to " + std::to_string(decoded.channels()) +
                             " channel(s) of " + std::to_string(decoded.elemSize1() * 8) + " bits");
  return {};
}

/// The decoded pixels as an Image (rows packed).
Image toImage(const cv::Mat& decoded, const std::string& encoding) {
  Image out;
  out.width = decoded.cols;
  out.height = decoded.rows;
  out.encoding = encoding;
  out.step = static_cast<std::size_t>(decoded.cols) * decoded.elemSize();
  out.data.resize(out.step * static_cast<std::size_t>(decoded.rows));
  for (int r = 0; r < decoded.rows; ++r)
    std::memcpy(out.data.data() + out.step * static_cast<std::size_t>(r), decoded.ptr(r), out.step);
  return out;
}

}  // namespace

DecodeResult decode(const std::string& format, const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size == 0) return decodeFailure(DecodeError::kEmpty, "no data");
  if (size > static_cast<std::size_t>(INT_MAX))
    return decodeFailure(DecodeError::kCorrupt, "stream of " + std::to_string(size) + " bytes is too large");
  std::string encoding, scheme;
  Codec codec;
  Layout layout;
  DecodeResult step = parseFormat(format, &encoding, &scheme, &codec, &layout);
  if (!step.ok()) return step;
  cv::Mat decoded;
  step = decodeStream(codec, scheme, data, size, &decoded);
  if (!step.ok()) return step;
  step = checkDecodedShape(decoded, &encoding, &layout);
  if (!step.ok()) return step;
  if (layout.swap_rb) cv::cvtColor(decoded, decoded, cv::COLOR_BGR2RGB);
  DecodeResult result;
  result.image = toImage(decoded, encoding);
  return result;
}

}  // namespace docking_image_transport
