/* fdi-book: a table wider than the text column is shown as cards (class fdi-stacked, laid out
   by fdi.css) when its cells carry data-label attributes; otherwise, or without JavaScript, it
   scrolls in its box with fdi.css's scroll shadow. Measured again after MathJax has typeset the
   page (maths changes the widths), when the window is resized (a phone turned sideways) and when
   a dropdown opens. */
(function () {
  "use strict";
  function fit() {
    document.querySelectorAll(".bd-article table").forEach(function (t) {
      if (!t.querySelector("td[data-label]")) return;
      t.classList.remove("fdi-stacked");
      if (t.offsetWidth > t.parentElement.clientWidth + 1) t.classList.add("fdi-stacked");
    });
  }
  var timer = null;
  window.addEventListener("resize", function () { clearTimeout(timer); timer = setTimeout(fit, 100); });
  document.addEventListener("toggle", fit, true);  // a table in a dropdown has no width until opened
  window.addEventListener("load", function () {
    var mj = window.MathJax && window.MathJax.startup && window.MathJax.startup.promise;
    (mj || Promise.resolve()).then(fit);
  });
})();
