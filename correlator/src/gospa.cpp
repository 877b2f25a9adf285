#include "ugv/correlator/gospa.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ugv/platform/assert.hpp"

namespace ugv::correlator {
namespace {

/// The Hungarian algorithm for rows <= cols (1-based potentials u, v; column 0 is the virtual start of each
/// augmenting path). Returns, per row, its column.
std::vector<int> assignRowsToColumns(const std::vector<double>& cost, std::size_t rows, std::size_t cols)
{
    constexpr double kInf = std::numeric_limits<double>::infinity();
    const auto at = [&](std::size_t row1, std::size_t col1) { return cost[(row1 - 1) * cols + (col1 - 1)]; };
    std::vector<double> u(rows + 1, 0.0);
    std::vector<double> v(cols + 1, 0.0);
    std::vector<std::size_t> rowOfCol(cols + 1, 0); // 0: free
    std::vector<std::size_t> previous(cols + 1, 0);
    for (std::size_t row = 1; row <= rows; ++row) {
        rowOfCol[0] = row;
        std::size_t col0 = 0;
        std::vector<double> slack(cols + 1, kInf);
        std::vector<bool> visited(cols + 1, false);
        do { // grow the shortest-path tree until it reaches a free column
            visited[col0] = true;
            const std::size_t row0 = rowOfCol[col0];
            double delta = kInf;
            std::size_t col1 = 0;
            for (std::size_t col = 1; col <= cols; ++col) {
                if (visited[col]) {
                    continue;
                }
                const double reduced = at(row0, col) - u[row0] - v[col];
                if (reduced < slack[col]) {
                    slack[col] = reduced;
                    previous[col] = col0;
                }
                if (slack[col] < delta) {
                    delta = slack[col];
                    col1 = col;
                }
            }
            for (std::size_t col = 0; col <= cols; ++col) {
                if (visited[col]) {
                    u[rowOfCol[col]] += delta;
                    v[col] -= delta;
                } else {
                    slack[col] -= delta;
                }
            }
            col0 = col1;
        } while (rowOfCol[col0] != 0);
        do { // augment along the path back to the start
            const std::size_t col1 = previous[col0];
            rowOfCol[col0] = rowOfCol[col1];
            col0 = col1;
        } while (col0 != 0);
    }
    std::vector<int> colOfRow(rows, -1);
    for (std::size_t col = 1; col <= cols; ++col) {
        if (rowOfCol[col] != 0) {
            colOfRow[rowOfCol[col] - 1] = static_cast<int>(col - 1);
        }
    }
    return colOfRow;
}

std::vector<double> transposed(const std::vector<double>& cost, std::size_t rows, std::size_t cols)
{
    std::vector<double> out(cost.size());
    for (std::size_t r = 0; r < rows; ++r) {
        for (std::size_t c = 0; c < cols; ++c) {
            out[c * rows + r] = cost[r * cols + c];
        }
    }
    return out;
}

} // namespace

std::vector<int> solveAssignment(const std::vector<double>& cost, std::size_t rows, std::size_t cols)
{
    UGV_EXPECTS(cost.size() == rows * cols);
    if (rows <= cols) {
        return assignRowsToColumns(cost, rows, cols);
    }
    const std::vector<int> rowOfCol = assignRowsToColumns(transposed(cost, rows, cols), cols, rows);
    std::vector<int> colOfRow(rows, -1);
    for (std::size_t col = 0; col < cols; ++col) {
        colOfRow[static_cast<std::size_t>(rowOfCol[col])] = static_cast<int>(col);
    }
    return colOfRow;
}

GospaResult gospa(const std::vector<Eigen::Vector2d>& truth, const std::vector<Eigen::Vector2d>& estimates,
                  const GospaParams& params)
{
    UGV_EXPECTS(params.cutoffM > 0.0 && params.order >= 1.0);
    const double p = params.order;
    const double cutoffP = std::pow(params.cutoffM, p);
    std::vector<double> distance(truth.size() * estimates.size());
    std::vector<double> cost(distance.size());
    for (std::size_t i = 0; i < truth.size(); ++i) {
        for (std::size_t j = 0; j < estimates.size(); ++j) {
            const std::size_t k = i * estimates.size() + j;
            distance[k] = (truth[i] - estimates[j]).norm();
            cost[k] = std::pow(std::min(distance[k], params.cutoffM), p);
        }
    }
    const std::vector<int> assignment = solveAssignment(cost, truth.size(), estimates.size());

    GospaResult result;
    result.truthToEstimate.assign(truth.size(), -1);
    for (std::size_t i = 0; i < truth.size(); ++i) {
        const int j = assignment[i];
        if (j < 0) {
            continue;
        }
        const double d = distance[i * estimates.size() + static_cast<std::size_t>(j)];
        if (d < params.cutoffM) {
            result.truthToEstimate[i] = j;
            result.localisationPart += std::pow(d, p);
            ++result.assigned;
        }
    }
    result.missed = truth.size() - result.assigned;
    result.falseCount = estimates.size() - result.assigned;
    result.missedPart = cutoffP / 2.0 * static_cast<double>(result.missed);
    result.falsePart = cutoffP / 2.0 * static_cast<double>(result.falseCount);
    result.total = std::pow(result.localisationPart + result.missedPart + result.falsePart, 1.0 / p);
    return result;
}

} // namespace ugv::correlator
