/* fdi-book: hover previews (sphinx-tippy) with their maths typeset, offline.
 *
 * Loaded after tippy.js on every page with previews (_ext/fdi_book.py, before the page's own
 * tips script creates the tooltips on window load). A preview holds the HTML of its target
 * (equation, figure caption, proposition) with the maths as TeX; it is typeset by MathJax the
 * first time it is shown. A page with maths of its own has MathJax already; a page without
 * (the ledger, the bibliography) gets window.fdiMathJax = {src, config} from the extension and
 * loads MathJax from the build only when a preview with maths is first shown.
 * On a touch screen a tap follows the link and a long press shows the preview.
 */
(function () {
  "use strict";
  if (!window.tippy) return;
  let loading = null;

  function mathJaxReady() {
    if (window.MathJax && window.MathJax.startup && window.MathJax.startup.promise) {
      return window.MathJax.startup.promise;
    }
    const lazy = window.fdiMathJax;
    if (!lazy) return null;  // the page's own MathJax is still loading: shown as TeX this time
    if (!loading) {
      // the book's configuration, without typesetting the page (it has no maths)
      window.MathJax = Object.assign({}, lazy.config,
        {startup: Object.assign({}, lazy.config.startup || {}, {typeset: false})});
      loading = new Promise(function (resolve, reject) {
        const s = document.createElement("script");
        s.src = lazy.src;
        s.async = true;
        s.onload = resolve;
        s.onerror = reject;
        document.head.appendChild(s);
      }).then(function () { return window.MathJax.startup.promise; });
    }
    return loading;
  }

  tippy.setDefaultProps({
    touch: ["hold", 500],
    // the preview replaces the browser's own tooltip (a citation's title: the whole entry)
    onCreate: function (instance) { instance.reference.removeAttribute("title"); },
    onMount: function (instance) {  // in the document: MathJax measures what it typesets
      const box = instance.popper;
      // a figure's image loads (lazily) once shown: place the preview again when it has
      box.querySelectorAll("img").forEach(function (img) {
        if (!img.complete) {
          img.addEventListener("load", function () {
            if (instance.popperInstance) instance.popperInstance.update();
          }, {once: true});
        }
      });
      if (box.dataset.fdiTypeset || !box.querySelector(".math")) return;
      const ready = mathJaxReady();
      if (!ready) return;
      ready.then(function () { return window.MathJax.typesetPromise([box]); })
        .then(function () {
          box.dataset.fdiTypeset = "1";
          if (instance.popperInstance) instance.popperInstance.update();
        })
        .catch(function (err) { console.warn("fdi-previews: maths not typeset", err); });
    },
  });
})();
