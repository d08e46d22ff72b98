// glu's documentation site: a click on a figure opens it at its natural size, with its caption; a click
// or Escape closes it. No network, no library.
document.addEventListener("DOMContentLoaded", function () {
  var box = document.createElement("div");
  box.className = "glu-lightbox";
  box.setAttribute("role", "dialog");
  box.innerHTML = '<figure><figcaption></figcaption><img alt=""></figure>';
  document.body.appendChild(box);
  var big = box.querySelector("img"), cap = box.querySelector("figcaption");
  function close() { box.classList.remove("open"); big.removeAttribute("src"); }
  box.addEventListener("click", close);
  document.addEventListener("keydown", function (e) { if (e.key === "Escape") { close(); } });
  document.querySelectorAll(".bd-article img").forEach(function (img) {
    img.addEventListener("click", function (e) {
      e.preventDefault();
      // the caption's text (its title and own sentence), the legend (the prose that interprets the
      // figure), then the file's name on a line of its own
      var fig = img.closest("figure");
      var text = fig ? fig.querySelector("figcaption .caption-text") : null;
      var legend = fig ? fig.querySelector("figcaption .legend") : null;
      var file = text ? text.querySelector(".glu-file") : null;
      cap.textContent = "";
      var head = document.createElement("span");
      if (text) {
        head.innerHTML = text.innerHTML;  // the site's own caption: bold title, code, links
        head.querySelectorAll(".glu-file").forEach(function (e) { e.remove(); });
      }
      cap.appendChild(head);
      if (legend) { cap.appendChild(document.createTextNode(" " + legend.textContent.trim())); }
      var name = document.createElement("span");
      name.className = "glu-file";
      name.textContent = file ? file.textContent.trim() : (img.getAttribute("alt") || "");
      cap.appendChild(name);
      big.src = img.currentSrc || img.src;
      big.alt = img.alt;
      box.classList.add("open");
      box.scrollTop = 0; box.scrollLeft = 0;
    });
  });
});
