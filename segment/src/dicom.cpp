#include "tactus/segment/dicom.hpp"
#include "tactus/core/file_io.hpp"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <map>
#include <sstream>
#include <thread>

#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmTrace.h>

#include "tactus/core/error.hpp"
#include "tactus/core/isolated.hpp"
#include "tactus/core/log.hpp"
#include "tactus/core/progress.hpp"

namespace fs = std::filesystem;

namespace tactus::segment {

namespace {

constexpr std::uint32_t kUndefined = 0xFFFFFFFFu;
constexpr int kMaxDepth = 32;  // nested sequences; real files use a handful
constexpr std::uint64_t kMaxFileBytes = std::uint64_t{4} << 30;

std::string trimmed(std::string s) {
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  std::size_t k = 0;
  while (k < s.size() && s[k] == ' ') ++k;
  return s.substr(k);
}

// Backslash-separated decimal strings (DS) as numbers; false when one is not a finite number.
bool decimals(const std::string& text, std::vector<double>& out) {
  out.clear();
  std::stringstream ss(text);
  std::string part;
  while (std::getline(ss, part, '\\')) {
    part = trimmed(part);
    if (!part.empty() && part[0] == '+') part.erase(0, 1);
    double v = 0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), v);
    if (part.empty() || ec != std::errc() || end != part.data() + part.size() || !std::isfinite(v)) return false;
    out.push_back(v);
  }
  return true;
}

// The element walk of one file: every tag, VR and length checked against the bytes that are
// there, sequences and encapsulated pixel data followed to any depth (within kMaxDepth).
class Walker {
 public:
  Walker(const std::string& bytes, std::string file, DicomSlice& out)
      : p_(reinterpret_cast<const unsigned char*>(bytes.data())), n_(bytes.size()), file_(std::move(file)), out_(out) {}

  void run() {
    if (n_ < 132 || std::memcmp(p_ + 128, "DICM", 4) != 0)
      throw InputError(file_, "", "a DICOM Part 10 file (128-byte preamble, then DICM)", "no DICM marker");
    std::size_t pos = 132;
    // The file meta group (0002,xxxx): always explicit VR little endian.
    while (pos + 8 <= n_ && u16le(pos) == 0x0002) pos = element(pos, n_, 0, true, false, true);
    const std::string ts = out_.transfer_syntax;
    if (ts.empty()) throw InputError(file_, "(0002,0010) TransferSyntaxUID", "a transfer syntax in the file meta group", "none");
    if (ts == "1.2.840.10008.1.2.1.99")
      throw InputError(file_, "(0002,0010) TransferSyntaxUID", "a transfer syntax tactus can check before decoding",
                       "deflated explicit VR (not supported)");
    const bool explicit_vr = ts != "1.2.840.10008.1.2";
    const bool big = ts == "1.2.840.10008.1.2.2";
    while (pos < n_) pos = element(pos, n_, 0, explicit_vr, big, false);
  }

 private:
  const unsigned char* p_;
  std::size_t n_;
  std::string file_;
  DicomSlice& out_;

  std::uint16_t u16le(std::size_t pos) const { return static_cast<std::uint16_t>(p_[pos] | (p_[pos + 1] << 8)); }
  std::uint16_t u16(std::size_t pos, bool big) const { return big ? static_cast<std::uint16_t>((p_[pos] << 8) | p_[pos + 1]) : u16le(pos); }
  std::uint32_t u32(std::size_t pos, bool big) const {
    return big ? (std::uint32_t{p_[pos]} << 24) | (std::uint32_t{p_[pos + 1]} << 16) | (std::uint32_t{p_[pos + 2]} << 8) | p_[pos + 3]
               : std::uint32_t{p_[pos]} | (std::uint32_t{p_[pos + 1]} << 8) | (std::uint32_t{p_[pos + 2]} << 16) | (std::uint32_t{p_[pos + 3]} << 24);
  }
  static std::string tag_name(std::uint16_t g, std::uint16_t e) {
    char s[16];
    std::snprintf(s, sizeof s, "(%04X,%04X)", g, e);
    return s;
  }
  [[noreturn]] void bad(std::size_t pos, std::uint16_t g, std::uint16_t e, const std::string& what) const {
    throw InputError(file_, "element " + tag_name(g, e) + " at byte " + std::to_string(pos), "a well-formed DICOM data element", what);
  }

  // One data element at pos inside [.., end); returns the position after it.
  std::size_t element(std::size_t pos, std::size_t end, int depth, bool explicit_vr, bool big, bool meta) {
    if (pos + 8 > end) bad(pos, 0, 0, "cut short (truncated)");
    const std::uint16_t g = u16(pos, big), e = u16(pos + 2, big);
    std::string vr;
    std::uint32_t len = 0;
    std::size_t value = 0;
    if (g == 0xFFFE) bad(pos, g, e, "an item or delimiter outside a sequence");
    if (explicit_vr) {
      vr.assign(reinterpret_cast<const char*>(p_ + pos + 4), 2);
      if (!std::isupper(static_cast<unsigned char>(vr[0])) || !std::isupper(static_cast<unsigned char>(vr[1]))) bad(pos, g, e, "no valid VR");
      static const char* long_form[] = {"OB", "OD", "OF", "OL", "OV", "OW", "SQ", "SV", "UC", "UN", "UR", "UT", "UV"};
      if (std::find_if(std::begin(long_form), std::end(long_form), [&](const char* v) { return vr == v; }) != std::end(long_form)) {
        if (pos + 12 > end) bad(pos, g, e, "cut short (truncated)");
        len = u32(pos + 8, big), value = pos + 12;
      } else {
        len = u16(pos + 6, big), value = pos + 8;
      }
    } else {
      len = u32(pos + 4, big), value = pos + 8;
    }
    if (len == kUndefined) {
      const bool pixels = g == 0x7FE0 && e == 0x0010;
      if (!(vr.empty() || vr == "SQ" || vr == "UN" || (pixels && (vr == "OB" || vr == "OW")))) bad(pos, g, e, "an undefined length on a " + vr);
      if (depth >= kMaxDepth) bad(pos, g, e, "sequences nested deeper than " + std::to_string(kMaxDepth));
      if (pixels) {
        out_.has_pixels = true;
        return fragments(value, end, g, e, big);
      }
      // Implicit VR or UN of undefined length: a sequence in implicit VR little endian (PS3.5 6.2.2).
      return sequence(value, end, kUndefined, depth + 1, vr == "UN" ? false : explicit_vr, vr == "UN" ? false : big, g, e);
    }
    if (len > end - value) bad(pos, g, e, "a length of " + std::to_string(len) + " bytes beyond the end (truncated)");
    if (vr == "SQ") {
      if (depth >= kMaxDepth) bad(pos, g, e, "sequences nested deeper than " + std::to_string(kMaxDepth));
      sequence(value, value + len, len, depth + 1, explicit_vr, big, g, e);
    } else if (depth == 0) {
      record(g, e, value, len, big, meta);
    }
    return value + len;
  }

  // Items of a sequence from pos: within [pos, pos + len) when len is defined, else up to its
  // delimiter. Returns the position after the sequence.
  std::size_t sequence(std::size_t pos, std::size_t end, std::uint32_t len, int depth, bool explicit_vr, bool big, std::uint16_t g, std::uint16_t e) {
    const std::size_t stop = len == kUndefined ? end : pos + len;
    while (true) {
      if (len != kUndefined && pos == stop) return pos;
      if (pos + 8 > stop) bad(pos, g, e, "a sequence cut short (truncated)");
      const std::uint16_t ig = u16(pos, big), ie = u16(pos + 2, big);
      const std::uint32_t il = u32(pos + 4, big);
      if (ig == 0xFFFE && ie == 0xE0DD) {
        if (len != kUndefined) bad(pos, g, e, "a delimiter in a sequence of defined length");
        return pos + 8;
      }
      if (ig != 0xFFFE || ie != 0xE000) bad(pos, g, e, "an item expected in the sequence");
      pos += 8;
      if (il == kUndefined) {
        while (true) {
          if (pos + 8 > stop) bad(pos, g, e, "an item cut short (truncated)");
          if (u16(pos, big) == 0xFFFE && u16(pos + 2, big) == 0xE00D) {
            pos += 8;
            break;
          }
          pos = element(pos, stop, depth, explicit_vr, big, false);
        }
      } else {
        if (il > stop - pos) bad(pos, g, e, "an item longer than its sequence (truncated)");
        const std::size_t item_end = pos + il;
        while (pos < item_end) pos = element(pos, item_end, depth, explicit_vr, big, false);
      }
    }
  }

  // Encapsulated pixel data: a basic offset table item, fragments, then the delimiter.
  std::size_t fragments(std::size_t pos, std::size_t end, std::uint16_t g, std::uint16_t e, bool big) {
    while (true) {
      if (pos + 8 > end) bad(pos, g, e, "encapsulated pixel data cut short (truncated)");
      const std::uint16_t ig = u16(pos, big), ie = u16(pos + 2, big);
      const std::uint32_t il = u32(pos + 4, big);
      if (ig == 0xFFFE && ie == 0xE0DD) return pos + 8;
      if (ig != 0xFFFE || ie != 0xE000 || il == kUndefined) bad(pos, g, e, "a pixel data fragment expected");
      if (il > end - pos - 8) bad(pos, g, e, "a fragment beyond the end (truncated)");
      pos += 8 + il;
    }
  }

  std::string text(std::size_t value, std::uint32_t len) const { return trimmed(std::string(reinterpret_cast<const char*>(p_ + value), len)); }

  void numbers(std::uint16_t g, std::uint16_t e, std::size_t value, std::uint32_t len, std::size_t count, double* out) const {
    std::vector<double> v;
    if (!decimals(text(value, len), v) || v.size() != count)
      throw InputError(file_, tag_name(g, e), std::to_string(count) + " decimal number(s)", "'" + text(value, len).substr(0, 60) + "'");
    std::copy(v.begin(), v.end(), out);
  }

  void record(std::uint16_t g, std::uint16_t e, std::size_t value, std::uint32_t len, bool big, bool meta) {
    const std::uint32_t key = (std::uint32_t{g} << 16) | e;
    auto us = [&]() -> int {
      if (len != 2) throw InputError(file_, tag_name(g, e), "one unsigned short (2 bytes)", std::to_string(len) + " bytes");
      return u16(value, big);
    };
    if (meta) {
      if (key == 0x00020010) out_.transfer_syntax = text(value, len);
      return;
    }
    switch (key) {
      case 0x00080016:
        out_.sop_class_uid = text(value, len);
        break;
      case 0x0008103E:
        out_.series_description = text(value, len);
        break;
      case 0x00080060:
        out_.modality = text(value, len);
        break;
      case 0x0020000E:
        out_.series_uid = text(value, len);
        break;
      case 0x00200032:
        numbers(g, e, value, len, 3, out_.position.data()), out_.has_position = true;
        break;
      case 0x00200037:
        numbers(g, e, value, len, 6, out_.orientation.data()), out_.has_orientation = true;
        break;
      case 0x00280002:
        out_.samples_per_pixel = us();
        break;
      case 0x00280010:
        out_.rows = us();
        break;
      case 0x00280011:
        out_.columns = us();
        break;
      case 0x00280030:
        numbers(g, e, value, len, 2, out_.pixel_spacing.data()), out_.has_pixel_spacing = true;
        break;
      case 0x00280100:
        out_.bits_allocated = us();
        break;
      case 0x00280103:
        out_.pixel_representation = us();
        break;
      case 0x00281052:
        numbers(g, e, value, len, 1, &out_.intercept);
        break;
      case 0x00281053:
        numbers(g, e, value, len, 1, &out_.slope);
        break;
      case 0x7FE00010:
        out_.has_pixels = true;
        break;
      default:
        break;
    }
  }
};

double dot(const double* a, const double* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Threads for `items` independent files: the cores (at most 8), one per 16 files at least.
unsigned worker_threads(std::size_t items) {
  const unsigned cores = std::max(1u, std::min(8u, std::thread::hardware_concurrency()));
  return static_cast<unsigned>(std::max<std::size_t>(1, std::min<std::size_t>(cores, items / 16)));
}

// Runs work(k) for k = 0..n-1 on worker_threads(n) std::threads (not OpenMP: its idle pool would
// keep spinning after the work, and it does not survive a fork into an isolated child), with a
// progress line; the first error in index order is rethrown once all are done.
template <class Work>
void for_each_file(const char* label, std::size_t n, Work&& work) {
  Progress progress(label, n);
  std::atomic<std::size_t> next{0}, done{0};
  std::vector<std::exception_ptr> failed(n);
  auto run = [&](bool report) {
    for (std::size_t k = next++; k < n; k = next++) {
      try {
        work(k);
      } catch (...) {
        failed[k] = std::current_exception();
      }
      const std::size_t d = ++done;
      if (report) progress.update(d);
    }
  };
  std::vector<std::thread> threads;
  for (unsigned t = 1; t < worker_threads(n); ++t) threads.emplace_back(run, false);
  run(true);
  for (auto& t : threads) t.join();
  progress.finish();
  for (const auto& e : failed)
    if (e) std::rethrow_exception(e);
}

std::string describe(const DicomSeries& s) {
  return s.uid + " (" + (s.description.empty() ? std::string("no description") : "'" + s.description + "'") + ", " + std::to_string(s.slices.size()) +
         " images)";
}

// The image checks one file must pass before it joins a series.
void check_image(const DicomSlice& s) {
  const std::string f = s.file.string();
  if (!s.has_pixels) throw InputError(f, "(7FE0,0010) PixelData", "an image", "no pixel data");
  if (s.rows < 1 || s.columns < 1)
    throw InputError(f, "(0028,0010/0011) Rows/Columns", "at least 1 x 1 pixels", std::to_string(s.rows) + " x " + std::to_string(s.columns));
  if (s.samples_per_pixel != 1) throw InputError(f, "(0028,0002) SamplesPerPixel", "1 (a grey CT image)", std::to_string(s.samples_per_pixel));
  if (s.bits_allocated != 8 && s.bits_allocated != 16) throw InputError(f, "(0028,0100) BitsAllocated", "8 or 16", std::to_string(s.bits_allocated));
  if (s.bits_stored != 0 && (s.bits_stored > s.bits_allocated || (s.high_bit >= 0 && s.high_bit != s.bits_stored - 1)))
    throw InputError(f, "(0028,0101/0102) BitsStored/HighBit", "BitsStored <= BitsAllocated and HighBit = BitsStored - 1",
                     std::to_string(s.bits_stored) + " / " + std::to_string(s.high_bit));
  if (s.pixel_representation != 0 && s.pixel_representation != 1)
    throw InputError(f, "(0028,0103) PixelRepresentation", "0 (unsigned) or 1 (signed)", std::to_string(s.pixel_representation));
  if (!s.has_position) throw InputError(f, "(0020,0032) ImagePositionPatient", "the slice's position", "missing");
  if (!s.has_orientation) throw InputError(f, "(0020,0037) ImageOrientationPatient", "the slice's orientation", "missing");
  if (!s.has_pixel_spacing) throw InputError(f, "(0028,0030) PixelSpacing", "the pixel size", "missing");
  for (double h : s.pixel_spacing)
    if (!(h >= 1e-4 && h <= 1e3)) throw InputError(f, "(0028,0030) PixelSpacing", "positive sizes in mm (0.0001 to 1000)", std::to_string(h));
  const double* r = s.orientation.data();
  const double* c = s.orientation.data() + 3;
  if (std::abs(dot(r, r) - 1) > 1e-3 || std::abs(dot(c, c) - 1) > 1e-3 || std::abs(dot(r, c)) > 1e-3)
    throw InputError(f, "(0020,0037) ImageOrientationPatient", "two orthogonal unit vectors", "not orthonormal");
  if (!(s.slope != 0 && std::abs(s.slope) < 1e6 && std::abs(s.intercept) < 1e6))
    throw InputError(f, "(0028,1053) RescaleSlope", "a non-zero slope and an intercept within 1e6",
                     std::to_string(s.slope) + ", " + std::to_string(s.intercept));
  for (double x : s.position)
    if (std::abs(x) > 1e6) throw InputError(f, "(0020,0032) ImagePositionPatient", "a position within 1 km", std::to_string(x));
}

}  // namespace

bool looks_like_dicom(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return false;  // a FIFO or device would block the read
  std::ifstream in(file, std::ios::binary);
  char head[132] = {};
  in.read(head, 132);
  return in.gcount() == 132 && std::memcmp(head + 128, "DICM", 4) == 0;
}

DicomSlice scan_dicom_file(const fs::path& file) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  if (ec) throw InputError(file.string(), "", "a readable DICOM file", "unreadable");
  if (size > kMaxFileBytes) throw InputError(file.string(), "", "a DICOM file of at most 4 GB", std::to_string(size) + " bytes");
  std::ifstream in(file, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), {});
  DicomSlice s;
  s.file = file;
  Walker(bytes, file.string(), s).run();
  return s;
}

bool is_dicom_folder(const fs::path& folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec) || fs::exists(folder / "stack.json", ec)) return false;
  for (const auto& entry : fs::directory_iterator(folder, ec))
    if (entry.is_regular_file(ec) && looks_like_dicom(entry.path())) return true;
  return false;
}

std::vector<DicomSeries> list_dicom_series(const fs::path& folder) {
  const std::string dir = folder.string();
  if (!fs::is_directory(folder)) throw InputError(dir, "", "a folder of DICOM files", "no such folder");
  std::vector<fs::path> files;
  std::size_t others = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (!entry.is_regular_file()) continue;
    if (looks_like_dicom(entry.path()))
      files.push_back(entry.path());
    else
      ++others;
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) throw InputError(dir, "", "DICOM files (a 128-byte preamble, then DICM)", "none");
  std::map<std::string, DicomSeries> by_uid;
  std::size_t not_images = 0;
  // The walks are independent: in parallel, the first error in file order reported.
  std::vector<DicomSlice> scanned(files.size());
  for_each_file("scan DICOM files", files.size(), [&](std::size_t k) { scanned[k] = scan_dicom_file(files[k]); });
  for (std::size_t k = 0; k < files.size(); ++k) {
    DicomSlice s = std::move(scanned[k]);
    if (!s.has_pixels) {  // a DICOMDIR, a report, a presentation state: not part of any image series
      ++not_images;
      continue;
    }
    if (s.series_uid.empty()) throw InputError(files[k].string(), "(0020,000E) SeriesInstanceUID", "the series the image belongs to", "missing");
    DicomSeries& series = by_uid[s.series_uid];
    series.uid = s.series_uid;
    if (series.description.empty()) series.description = s.series_description;
    series.slices.push_back(std::move(s));
  }
  if (others || not_images)
    log::info() << "DICOM folder " << dir << ": " << others << " other file(s) and " << not_images << " DICOM file(s) without an image left aside";
  std::vector<DicomSeries> out;
  for (auto& [uid, s] : by_uid) out.push_back(std::move(s));
  if (out.empty()) throw InputError(dir, "", "DICOM images", "DICOM files without pixel data only");
  return out;
}

namespace {

// The series asked for (--series), or the folder's only one; refuses naming the folder's series.
DicomSeries& choose_series(std::vector<DicomSeries>& all, const std::string& series_uid, const std::string& dir) {
  std::string listing;
  for (const DicomSeries& s : all) listing += "\n  " + describe(s);
  DicomSeries* chosen = nullptr;
  if (!series_uid.empty()) {
    for (DicomSeries& s : all)
      if (s.uid == series_uid) chosen = &s;
    if (!chosen) throw InputError(dir, "--series", "one of the folder's series:" + listing, series_uid);
  } else if (all.size() > 1) {
    throw InputError(dir, "--series", "a choice of series: the folder holds " + std::to_string(all.size()) + ":" + listing, "none given");
  } else {
    chosen = &all.front();
  }
  return *chosen;
}

// Every slice decodable and of the first one's size, pixel format, pixel size and orientation;
// at least two (the slice spacing comes from their positions).
void check_slices_alike(const std::vector<DicomSlice>& slices, const std::string& dir, const std::string& uid) {
  for (const DicomSlice& s : slices) check_image(s);
  const DicomSlice& first = slices.front();
  // Segmentation works in Hounsfield units; another modality has no such scale (an MR series
  // segmented with CT thresholds found tissue with no note at all).
  if (!first.modality.empty() && first.modality != "CT")
    log::warn(first.file.string() + ": (0008,0060) Modality is " + first.modality +
              ", not CT: its values are not Hounsfield units, so the default thresholds may find the wrong tissue; "
              "check the segmentation, or give --body-threshold and --bone-threshold in its own units");
  for (const DicomSlice& s : slices) {
    const std::string f = s.file.string();
    if (s.rows != first.rows || s.columns != first.columns)
      throw InputError(f, "(0028,0010/0011) Rows/Columns",
                       std::to_string(first.columns) + " x " + std::to_string(first.rows) + " like " + first.file.filename().string(),
                       std::to_string(s.columns) + " x " + std::to_string(s.rows));
    if (s.bits_allocated != first.bits_allocated || s.pixel_representation != first.pixel_representation)
      throw InputError(f, "(0028,0100/0103) pixel format", "the pixel format of " + first.file.filename().string(), "another");
    for (int i = 0; i < 2; ++i)
      if (std::abs(s.pixel_spacing[i] - first.pixel_spacing[i]) > 1e-4 * first.pixel_spacing[i])
        throw InputError(f, "(0028,0030) PixelSpacing", "the pixel size of " + first.file.filename().string(), "another");
    for (int i = 0; i < 6; ++i)
      if (std::abs(s.orientation[i] - first.orientation[i]) > 1e-4)
        throw InputError(f, "(0020,0037) ImageOrientationPatient", "the orientation of " + first.file.filename().string(), "another");
  }
  if (slices.size() < 2) throw InputError(dir, "series " + uid, "at least 2 slices (the slice spacing comes from their positions)", "1");
}

// Sorts the slices along the normal n and returns their spacing (mm), refusing uneven spacing, a
// missing slice or a gantry tilt.
double stack_along_normal(std::vector<DicomSlice>& slices, const double n[3], const std::string& dir) {
  std::sort(slices.begin(), slices.end(),
            [&](const DicomSlice& a, const DicomSlice& b) { return dot(a.position.data(), n) < dot(b.position.data(), n); });
  std::vector<double> gaps;
  for (std::size_t k = 1; k < slices.size(); ++k) gaps.push_back(dot(slices[k].position.data(), n) - dot(slices[k - 1].position.data(), n));
  std::vector<double> sorted_gaps = gaps;
  std::nth_element(sorted_gaps.begin(), sorted_gaps.begin() + static_cast<long>(sorted_gaps.size() / 2), sorted_gaps.end());
  const double dz = sorted_gaps[sorted_gaps.size() / 2];
  if (!(dz >= 1e-4 && dz <= 1e3))
    throw InputError(dir, "(0020,0032) ImagePositionPatient", "distinct slice positions (0.0001 to 1000 mm apart)", std::to_string(dz) + " mm");
  for (std::size_t k = 0; k < gaps.size(); ++k) {
    const auto& a = slices[k];
    const auto& b = slices[k + 1];
    if (std::abs(gaps[k] - dz) > 0.01 * dz)
      throw InputError(b.file.string(), "(0020,0032) ImagePositionPatient", "evenly spaced slices (" + std::to_string(dz) + " mm, within 1 %)",
                       std::to_string(gaps[k]) + " mm after " + a.file.filename().string() + (gaps[k] > 1.5 * dz ? " (a missing slice?)" : ""));
    // Gantry tilt: consecutive positions offset across the slice normal.
    double d[3];
    for (int i = 0; i < 3; ++i) d[i] = b.position[i] - a.position[i] - gaps[k] * n[i];
    if (std::sqrt(dot(d, d)) > 0.01 * dz)
      throw InputError(b.file.string(), "(0020,0032) ImagePositionPatient",
                       "slices stacked along their normal (no gantry tilt: resample a tilted series first)",
                       "an offset of " + std::to_string(std::sqrt(dot(d, d))) + " mm across the normal from " + a.file.filename().string());
  }
  return dz;
}

// The stored pixel values of every slice, decoded by GDCM in a child process (the walked, checked
// files), slice after slice.
std::vector<std::uint16_t> decode_stored_values(const std::vector<fs::path>& paths, std::size_t per_slice, int bytes_per_pixel,
                                                const std::string& dir) {
  const std::string bytes = run_isolated(
      dir, "DICOM image",
      [&](ByteWriter& w) {
        gdcm::Trace::ErrorOff(), gdcm::Trace::WarningOff(), gdcm::Trace::DebugOff();  // (in the child: tactus says what failed, once)
        std::vector<std::uint16_t> stored(per_slice * paths.size());
        // Slices decode independently, each with its own reader (and each thread its own buffer);
        // the first error in slice order is reported.
        for_each_file("decode DICOM slices", paths.size(), [&](std::size_t k) {
          thread_local std::vector<char> buffer;
          buffer.resize(per_slice * static_cast<std::size_t>(bytes_per_pixel));
          gdcm::ImageReader reader;
          reader.SetFileName(paths[k].string().c_str());
          if (!reader.Read()) throw InputError(paths[k].string(), "(7FE0,0010) PixelData", "pixel data GDCM can decode", "undecodable");
          const gdcm::Image& image = reader.GetImage();
          // Native (unencapsulated) pixel data must hold every pixel: GDCM pads a short element
          // with zeros (seen: 100 of 2,112 bytes decoded as a mostly black slice, exit 0).
          const gdcm::DataElement& pixels = reader.GetFile().GetDataSet().GetDataElement(gdcm::Tag(0x7fe0, 0x0010));
          if (const gdcm::ByteValue* raw = pixels.GetByteValue(); raw && raw->GetLength() < buffer.size())
            throw InputError(paths[k].string(), "(7FE0,0010) PixelData", std::to_string(buffer.size()) + " bytes of pixels (rows x columns x bytes)",
                             std::to_string(raw->GetLength()) + " bytes (truncated)");
          if (image.GetBufferLength() != buffer.size())
            throw InputError(paths[k].string(), "(7FE0,0010) PixelData", std::to_string(buffer.size()) + " bytes of pixels",
                             std::to_string(image.GetBufferLength()) + " bytes decoded");
          if (!image.GetBuffer(buffer.data()))
            throw InputError(paths[k].string(), "(7FE0,0010) PixelData", "pixel data GDCM can decode", "undecodable");
          std::uint16_t* out = stored.data() + k * per_slice;
          if (bytes_per_pixel == 2)
            std::memcpy(out, buffer.data(), buffer.size());
          else
            for (std::size_t i = 0; i < per_slice; ++i) out[i] = static_cast<unsigned char>(buffer[i]);
        });
        w.put_vector(stored);
      },
      IsolationLimits{30.0 + 0.5 * static_cast<double>(paths.size()), 0});
  ByteReader reader(bytes);
  return reader.get_vector<std::uint16_t>();
}

// The stored values to Hounsfield units, slice by slice: a series may carry a different
// slope/intercept on each image.
void rescale_to_hounsfield(const std::vector<DicomSlice>& slices, const std::vector<std::uint16_t>& stored, std::size_t per_slice, float* hu_of) {
  const DicomSlice& first = slices.front();
  for (std::size_t k = 0; k < slices.size(); ++k) {
    const double slope = slices[k].slope, intercept = slices[k].intercept;
    const std::uint16_t* in = stored.data() + k * per_slice;
    float* hu = hu_of + k * per_slice;
    // Only the low BitsStored bits are the pixel (the rest may hold anything, e.g. retired
    // overlays); a signed pixel's sign is its bit BitsStored - 1.
    const int stored_bits = first.bits_stored > 0 ? first.bits_stored : first.bits_allocated;
    const std::uint32_t mask = (1u << stored_bits) - 1u, sign = 1u << (stored_bits - 1);
    for (std::size_t i = 0; i < per_slice; ++i) {
      const std::uint32_t raw = in[i] & mask;
      const double v =
          first.pixel_representation == 1 && (raw & sign) ? static_cast<double>(raw) - static_cast<double>(mask) - 1.0 : static_cast<double>(raw);
      hu[i] = static_cast<float>(slope * v + intercept);
    }
  }
}

}  // namespace

SliceStack read_dicom_series(const fs::path& folder, const std::string& series_uid) {
  const std::string dir = folder.string();
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<DicomSeries> all = list_dicom_series(folder);
  const double scan_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  DicomSeries& chosen = choose_series(all, series_uid, dir);
  std::vector<DicomSlice>& slices = chosen.slices;
  check_slices_alike(slices, dir, chosen.uid);
  const DicomSlice& first = slices.front();
  // Volume axes: x along the row cosine (column index), y along the column cosine (row index),
  // z along their cross product, the slice normal; any orthonormal orientation is carried as the
  // volume's direction (through labels.h5 to the mesh's coordinates).
  const double* r = first.orientation.data();
  const double* c = first.orientation.data() + 3;
  const double n[3] = {r[1] * c[2] - r[2] * c[1], r[2] * c[0] - r[0] * c[2], r[0] * c[1] - r[1] * c[0]};
  const double dz = stack_along_normal(slices, n, dir);
  const DicomSlice& lowest = slices.front();  // (sorted now)
  const int nx = lowest.columns, ny = lowest.rows, nz = static_cast<int>(slices.size());
  const std::array<double, 3> spacing{lowest.pixel_spacing[1] * 1e-3, lowest.pixel_spacing[0] * 1e-3, dz * 1e-3};
  const std::array<double, 3> origin{slices[0].position[0] * 1e-3, slices[0].position[1] * 1e-3, slices[0].position[2] * 1e-3};
  validate_volume_geometry({nx, ny, nz}, spacing, origin, sizeof(float) + sizeof(std::uint16_t), dir, "DICOM series " + chosen.uid);
  std::vector<fs::path> paths;
  for (const DicomSlice& s : slices) paths.push_back(s.file);
  const std::size_t per_slice = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
  const std::vector<std::uint16_t> stored = decode_stored_values(paths, per_slice, lowest.bits_allocated / 8, dir);
  log::verbose() << "DICOM: walked " << all.size() << " series in " << scan_s << " s, decoded " << paths.size() << " slices in "
                 << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() - scan_s << " s";
  SliceStack out;
  out.hu = Volume<float>({nx, ny, nz}, spacing, origin);
  out.hu.direction = {r[0], c[0], n[0], r[1], c[1], n[1], r[2], c[2], n[2]};  // columns: row, column, slice normal
  validate_direction(out.hu.direction, lowest.file.string(), "(0020,0037) ImageOrientationPatient");
  if (stored.size() != out.hu.size()) throw InputError(dir, "", "slices of one size", "a malformed read");
  out.bit_depth = lowest.bits_allocated;
  out.files = slices.size();
  out.source = "DICOM series " + chosen.uid;
  rescale_to_hounsfield(slices, stored, per_slice, out.hu.data.data());
  return out;
}

}  // namespace tactus::segment
