#pragma once

/// @file
/// Finding left/right image pairs in a folder for the calibrate and rectify commands: `left<rest>` pairs
/// with `right<rest>` (left01.jpg/right01.jpg, left_03.png/right_03.png). Host tool only.

#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "ugv/platform/error.hpp"
#include "ugv/platform/result.hpp"

namespace ugv::tool {

struct PairFiles {
    std::string name; ///< "left01.jpg/right01.jpg"
    std::filesystem::path left;
    std::filesystem::path right;
};

struct PairListing {
    std::vector<PairFiles> pairs;      ///< sorted by name
    std::vector<std::string> unpaired; ///< "left07.jpg: no matching right07.jpg"
};

/// Lists `dir`; an error when it is missing or not a folder. Only image files (png, jpg, jpeg, bmp, pgm, ppm,
/// tif, tiff) count.
Result<PairListing, Error> listPairs(const std::filesystem::path& dir);

/// Refuses an image whose header (PNG, JPEG, BMP, PGM/PPM) declares a side above adapters::kMaxImageSide or none,
/// before anything is decoded (a 875 KB PNG declaring 30000x30000 cost imread 1.8 GB and 11 s). Other formats pass
/// (OpenCV's own limit of 2^30 pixels applies).
/// @return an error naming the file, the declared size and the limit
Result<void, Error> checkImageHeader(const std::filesystem::path& path);

/// Reads an image with cv::imread `flags` after checkImageHeader(); empty on failure, with the reason ("file not
/// found", the header's refusal, "not a readable image") in `why` when given.
cv::Mat readImage(const std::filesystem::path& path, int flags, std::string* why = nullptr);

/// True for a JPEG file (by its extension: .jpg, .jpeg, any case).
bool isJpeg(const std::filesystem::path& path);

/// What `detect` and `recording import` say once when the pairs are JPEG: both images' 8 x 8 compression blocks sit at
/// the same columns, a pattern that matches at disparities that are multiples of 8; the detector takes no drop from
/// such matches where both images show the blocks, so a real drop at such a disparity is Unknown (vision/README.md,
/// "A drop is not the blocks' edges").
extern const char* const kJpegPairsWarning;

/// readImage() as 8-bit grey.
cv::Mat readGrey(const std::filesystem::path& path, std::string* why = nullptr);

/// Parses "9x6" into inner corners (each in [2, 50]).
Result<cv::Size, Error> parseBoard(const std::string& command, const std::string& text);

} // namespace ugv::tool
