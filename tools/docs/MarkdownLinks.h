#pragma once
// Relative links of Markdown pages: every [text](path) and [text](path#anchor) must name a file
// or folder that exists, and an anchor must be the slug of a heading of the target page.
#include <string>
#include <vector>

namespace stereo_fusion {

/// The anchors of the headings of Markdown `text`, as GitHub and GitLab make them: lower case,
/// punctuation dropped, spaces to '-', a repeated heading getting "-1", "-2", ...; headings
/// inside code fences do not count.
std::vector<std::string> markdownHeadingAnchors(const std::string& text);

/// The relative links of the Markdown file `path` that do not resolve, each as
/// "file:line: target (why)". Links inside code fences and inline code are ignored, as are
/// absolute URLs (scheme://, mailto:). An unreadable `path` is itself one entry.
std::vector<std::string> brokenRelativeLinks(const std::string& path);

}  // namespace stereo_fusion
