#include "pair_files.hpp"

#include <algorithm>
#include <cctype>
#include <map>

#include <opencv2/imgcodecs.hpp>

namespace ugv::tool {
namespace {

constexpr int kMinBoardSide = 2;
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

cv::Mat readGrey(const std::filesystem::path& path)
{
    try {
        return cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception&) {
        return {};
    }
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
