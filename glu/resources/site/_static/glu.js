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
      // the caption's text (without its "#" anchor), then the legend: the sentence that interprets it
      var fig = img.closest("figure");
      var text = fig ? fig.querySelector("figcaption .caption-text") || fig.querySelector("figcaption") : null;
      var legend = fig ? fig.querySelector("figcaption .legend") : null;
      cap.textContent = (text ? text.textContent.trim() : (img.getAttribute("alt") || "")) +
        (legend && !text.contains(legend) ? " " + legend.textContent.trim() : "");
      big.src = img.currentSrc || img.src;
      big.alt = img.alt;
      box.classList.add("open");
      box.scrollTop = 0; box.scrollLeft = 0;
    });
  });
});
