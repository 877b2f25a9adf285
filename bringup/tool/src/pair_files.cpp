#include "ugv/tool/pair_files.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <climits>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "ugv/adapters/calibration_file.hpp"

namespace ugv::tool {
namespace {

constexpr int kMinBoardSide = 2;
/// Bytes read for a header: a JPEG's frame header may follow its EXIF segment (up to 64 KB).
constexpr std::size_t kHeaderBytes = 128U * 1024U;

std::uint32_t bigEndian(const unsigned char* p, int bytes)
{
    std::uint32_t v = 0;
    for (int i = 0; i < bytes; ++i) {
        v = (v << 8U) | p[i]; // pointer arithmetic over a checked buffer
    }
    return v;
}

/// The PGM/PPM header's "W H" after the magic, skipping comments.
std::optional<cv::Size> pnmSize(const unsigned char* h, std::size_t n)
{
    std::string text(reinterpret_cast<const char*>(h) + 2, std::min<std::size_t>(n - 2, 4096));
    std::istringstream in(text);
    std::vector<std::int64_t> numbers;
    std::string token;
    while (numbers.size() < 2 && in >> token) {
        if (token.front() == '#') {
            std::getline(in, token);
            continue;
        }
        try {
            numbers.push_back(std::stoll(token));
        } catch (const std::exception&) {
            return cv::Size(0, 0);
        }
    }
    if (numbers.size() < 2) {
        return cv::Size(0, 0);
    }
    const auto side = [](std::int64_t v) { return static_cast<int>(std::clamp<std::int64_t>(v, -1, INT32_MAX)); };
    return cv::Size(side(numbers[0]), side(numbers[1]));
}

/// The size the header of a PNG, JPEG, BMP or PGM/PPM declares; (0, 0) when it is cut short; nullopt for others.
std::optional<cv::Size> declaredSize(const unsigned char* h, std::size_t n)
{
    const auto side = [](std::uint32_t v) { return static_cast<int>(std::min<std::uint32_t>(v, INT32_MAX)); };
    if (n >= 8 && std::memcmp(h, "\x89PNG\r\n\x1a\n", 8) == 0) {
        if (n < 24 || std::memcmp(h + 12, "IHDR", 4) != 0) {
            return cv::Size(0, 0);
        }
        return cv::Size(side(bigEndian(h + 16, 4)), side(bigEndian(h + 20, 4)));
    }
    if (n >= 2 && h[0] == 0xFF && h[1] == 0xD8) { // JPEG: the first start-of-frame segment
        for (std::size_t i = 2; i + 9 < n;) {
            if (h[i] != 0xFF) {
                return cv::Size(0, 0);
            }
            const unsigned marker = h[i + 1];
            const bool frame = marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC;
            if (frame) {
                return cv::Size(side(bigEndian(h + i + 7, 2)), side(bigEndian(h + i + 5, 2)));
            }
            i += 2 + bigEndian(h + i + 2, 2);
        }
        return std::nullopt; // beyond what was read: OpenCV's own limit applies
    }
    if (n >= 26 && h[0] == 'B' && h[1] == 'M') { // BITMAPINFOHEADER: int32 LE width and height (negative: top-down)
        const auto le = [&h](std::size_t at) {
            return static_cast<std::int32_t>(static_cast<std::uint32_t>(h[at]) | (std::uint32_t{h[at + 1]} << 8U) |
                                             (std::uint32_t{h[at + 2]} << 16U) | (std::uint32_t{h[at + 3]} << 24U));
        };
        const auto magnitude = [](std::int32_t v) { return v == INT32_MIN ? INT32_MAX : std::abs(v); };
        return cv::Size(magnitude(le(18)), magnitude(le(22)));
    }
    if (n >= 3 && h[0] == 'P' && (h[1] == '2' || h[1] == '3' || h[1] == '5' || h[1] == '6')) {
        return pnmSize(h, n);
    }
    return std::nullopt;
}
constexpr int kMaxBoardSide = 50;

bool isImage(const std::filesystem::path& path)
{
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    for (const char* known : {".png", ".jpg", ".jpeg", ".bmp", ".pgm", ".ppm", ".tif", ".tiff"}) {
        if (ext == known) {
            return true;
        }
    }
    return false;
}

} // namespace

Result<PairListing, Error> listPairs(const std::filesystem::path& dir)
{
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) {
        return Unexpected(Error{dir.string(), "image folder not found", "give a folder holding left*/right* images"});
    }
    std::map<std::string, std::filesystem::path> lefts;
    std::map<std::string, std::filesystem::path> rights;
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::filesystem::path& path = it->path();
        if (!isImage(path)) {
            continue;
        }
        const std::string file = path.filename().string();
        if (file.rfind("left", 0) == 0) {
            lefts[file.substr(4)] = path;
        } else if (file.rfind("right", 0) == 0) {
            rights[file.substr(5)] = path;
        }
    }
    if (ec) {
        return Unexpected(Error{dir.string(), "cannot list the folder: " + ec.message(), "check its permissions"});
    }
    PairListing listing;
    for (const auto& [rest, left] : lefts) {
        const auto right = rights.find(rest);
        if (right == rights.end()) {
            listing.unpaired.push_back("left" + rest + ": no matching right" + rest);
            continue;
        }
        listing.pairs.push_back({"left" + rest + "/right" + rest, left, right->second});
    }
    for (const auto& [rest, right] : rights) {
        if (lefts.count(rest) == 0) {
            listing.unpaired.push_back("right" + rest + ": no matching left" + rest);
        }
    }
    return listing;
}

Result<void, Error> checkImageHeader(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    std::array<unsigned char, kHeaderBytes> h{};
    in.read(reinterpret_cast<char*>(h.data()), static_cast<std::streamsize>(h.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    const std::optional<cv::Size> size = declaredSize(h.data(), n);
    if (!size) {
        return {};
    }
    if (size->width < 1 || size->height < 1 || size->width > adapters::kMaxImageSide ||
        size->height > adapters::kMaxImageSide) {
        return Unexpected(Error{path.string(),
                                "the header declares " + std::to_string(size->width) + "x" +
                                    std::to_string(size->height) + " pixels, outside 1.." +
                                    std::to_string(adapters::kMaxImageSide) + " per side",
                                "give a camera image (the file is damaged or not one)"});
    }
    return {};
}

cv::Mat readImage(const std::filesystem::path& path, int flags, std::string* why)
{
    std::string reason;
    std::error_code ec;
    cv::Mat image;
    if (!std::filesystem::is_regular_file(path, ec)) {
        reason = "file not found";
    } else if (auto header = checkImageHeader(path); !header) {
        reason = header.error().what;
    } else {
        try {
            image = cv::imread(path.string(), flags);
        } catch (const cv::Exception&) {
            image.release();
        }
        if (image.empty()) {
            reason = "not a readable image";
        }
    }
    if (why != nullptr) {
        *why = reason;
    }
    return image;
}

bool isJpeg(const std::filesystem::path& path)
{
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return extension == ".jpg" || extension == ".jpeg";
}

const char* const kJpegPairsWarning =
    "the pairs are JPEG: both images' 8x8 compression blocks sit at the same columns and match at disparities that "
    "are multiples of 8; where both images show the blocks such a match is no evidence of a drop, so a real drop "
    "seen at such a disparity is Unknown (vision/README.md, \"A drop is not the blocks' edges\"); use lossless "
    "images (PNG) where you have them";

cv::Mat readGrey(const std::filesystem::path& path, std::string* why)
{
    return readImage(path, cv::IMREAD_GRAYSCALE, why);
}

Result<cv::Size, Error> parseBoard(const std::string& command, const std::string& text)
{
    const auto bad = [&] {
        return Unexpected(Error{"ugvsense " + command + " --board", "bad board '" + text + "'",
                                "give the inner corners as WxH, e.g. 9x6, each in [2, 50]"});
    };
    const auto x = text.find('x');
    if (x == std::string::npos || x == 0 || x + 1 >= text.size()) {
        return bad();
    }
    const std::string w = text.substr(0, x);
    const std::string h = text.substr(x + 1);
    const auto digits = [](const std::string& s) {
        return s.size() <= 3 && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
    };
    if (!digits(w) || !digits(h)) {
        return bad();
    }
    const cv::Size size(std::stoi(w), std::stoi(h));
    if (size.width < kMinBoardSide || size.height < kMinBoardSide || size.width > kMaxBoardSide ||
        size.height > kMaxBoardSide) {
        return bad();
    }
    return size;
}

} // namespace ugv::tool
