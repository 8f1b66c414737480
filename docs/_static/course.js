// The course site. From a file:// page the JupyterLite link cannot work (browsers do not let
// it start Python there): say so under each notebook's title instead of leaving a dead link.
document.addEventListener("DOMContentLoaded", function () {
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
