// The course site. From a file:// page the JupyterLite link cannot work (browsers do not let
// it start Python there): say so under each notebook's title instead of leaving a dead link.
document.addEventListener("DOMContentLoaded", function () {
  // A notebook's figure is scaled to the column on a phone: a tap opens it at full size.
  document.querySelectorAll(".bd-article .cell_output img").forEach(function (img) {
    if (img.closest("a")) {
      return;
    }
    var link = document.createElement("a");
    link.href = img.getAttribute("src");
    link.className = "course-full-figure";
    img.replaceWith(link);
    link.appendChild(img);
  });
  // Accessible names (axe-core, issue 39): the theme's search button says "Search Ctrl+K" but is
  // labelled "Search" (a label must contain the visible text); the sidebar's expand toggles are
  // <summary> elements with an icon and no name.
  document.querySelectorAll("button.search-button__button[aria-label]").forEach(function (b) {
    b.setAttribute("aria-label", b.textContent.replace(/\s+/g, " ").trim() || "Search");
  });
  document.querySelectorAll("summary").forEach(function (summary) {
    if (summary.textContent.trim() || summary.hasAttribute("aria-label")) {
      return;
    }
    var item = summary.closest("li");
    var link = item && item.querySelector("a");
    summary.setAttribute(
      "aria-label",
      link ? "Show the pages under " + link.textContent.trim() : "Show more"
    );
  });
  if (location.protocol !== "file:") {
    return;
  }
  document.querySelectorAll("p.course-launch").forEach(function (para) {
    para.classList.add("course-launch-unavailable");
    para.innerHTML =
      "To run this notebook in your browser, serve the site over http: " +
      "<code>python -m http.server --directory SITE_FOLDER 8000</code>, then open " +
      "<code>http://localhost:8000/</code> (a page opened from a file cannot start Python).";
  });
});
