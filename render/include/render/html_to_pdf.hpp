#pragma once
// PDF of an HTML page through headless Chromium's print (the page's own @page size and margins):
// what a certificate is archived and sent as.

#include <string>

namespace calstand::analysis {

/// The Chromium binary on PATH (chromium, chromium-browser, google-chrome). Throws
/// core::InputError naming chromium when there is none.
std::string find_chromium();

/// Prints `html` (a self-contained page) to the PDF file `pdf_path`. The file appears whole or
/// not at all (printed beside it, then renamed). Throws core::InputError naming chromium when it
/// is missing, fails or takes more than two minutes, and naming `pdf_path` when it cannot be
/// written.
void html_to_pdf(const std::string& html, const std::string& pdf_path);

}  // namespace calstand::analysis
