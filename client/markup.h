// Text placed into HTML and SVG markup by the comparison report.
#pragma once
#include <string>

namespace pf::client {

// `s` with the characters that markup gives meaning to (& < > ") written as entities.
inline std::string escapeMarkup(const std::string &s) {
    std::string out;
    for (const char c : s) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

}  // namespace pf::client
