// Pan and zoom for the diagram graphs. Every SVG image wrapped in a link
// ([![...](graph.svg)](graph.svg)) is shown in a frame: the mouse wheel zooms
// around the pointer, dragging pans, "+", "-" and "fit" zoom, a double click fits,
// and a click (without a drag) opens the full-size SVG. Without JavaScript the image
// is a plain link to the SVG.
(function () {
  "use strict";
  var MAX_ZOOM = 24;

  function enhance(link) {
    var img = link.querySelector("img");
    if (!img || link.closest(".svg-zoom")) return;
    var holder = link.parentElement && link.parentElement.tagName === "P" &&
      link.parentElement.children.length === 1 ? link.parentElement : link;
    var frame = document.createElement("div");
    frame.className = "svg-zoom";
    var bar = document.createElement("div");
    bar.className = "svg-zoom__bar";
    var view = document.createElement("div");
    view.className = "svg-zoom__view";
    holder.parentNode.insertBefore(frame, holder);
    frame.appendChild(bar);
    frame.appendChild(view);
    view.appendChild(holder);
    img.draggable = false;

    var zoom = 1;
    function setZoom(next, x, y) {
      next = Math.min(Math.max(next, 1), MAX_ZOOM);
      var rect = view.getBoundingClientRect();
      if (x === undefined) { x = rect.width / 2; y = rect.height / 2; }
      var fx = (view.scrollLeft + x) / img.offsetWidth;
      var fy = (view.scrollTop + y) / img.offsetHeight;
      zoom = next;
      img.style.width = (100 * zoom) + "%";
      view.scrollLeft = fx * img.offsetWidth - x;
      view.scrollTop = fy * img.offsetHeight - y;
      frame.classList.toggle("svg-zoom--zoomed", zoom > 1);
    }
    function button(text, title, action) {
      var b = document.createElement("button");
      b.type = "button";
      b.textContent = text;
      b.title = title;
      b.addEventListener("click", action);
      bar.appendChild(b);
    }
    var hint = document.createElement("span");
    hint.textContent = "scroll to zoom, drag to pan, click to open the SVG";
    bar.appendChild(hint);
    button("+", "zoom in", function () { setZoom(zoom * 1.5); });
    button("\u2212", "zoom out", function () { setZoom(zoom / 1.5); });
    button("fit", "fit the width", function () { setZoom(1); });
    button("1:1", "the graph at its own size", function () {
      setZoom((img.naturalWidth || 4 * view.clientWidth) / view.clientWidth, 0, 0);
    });

    view.addEventListener("wheel", function (event) {
      event.preventDefault();
      var rect = view.getBoundingClientRect();
      setZoom(zoom * Math.exp(-event.deltaY * 0.002),
              event.clientX - rect.left, event.clientY - rect.top);
    }, {passive: false});
    view.addEventListener("dblclick", function (event) {
      event.preventDefault();
      setZoom(1);
    });

    var drag = null, dragged = false;
    view.addEventListener("pointerdown", function (event) {
      if (event.button !== 0) return;
      drag = {x: event.clientX, y: event.clientY,
              left: view.scrollLeft, top: view.scrollTop};
      dragged = false;
    });
    window.addEventListener("pointermove", function (event) {
      if (!drag) return;
      var dx = event.clientX - drag.x, dy = event.clientY - drag.y;
      if (Math.abs(dx) + Math.abs(dy) > 4) {
        dragged = true;
        frame.classList.add("svg-zoom--dragging");
      }
      view.scrollLeft = drag.left - dx;
      view.scrollTop = drag.top - dy;
    });
    window.addEventListener("pointerup", function () {
      drag = null;
      frame.classList.remove("svg-zoom--dragging");
    });
    link.addEventListener("click", function (event) {
      if (dragged) { event.preventDefault(); dragged = false; }
    });
    link.target = "_blank";
  }

  function run() {
    var images = document.querySelectorAll('.md-typeset a > img[src$=".svg"]');
    Array.prototype.forEach.call(images, function (img) { enhance(img.parentElement); });
  }
  if (typeof document$ !== "undefined") {
    document$.subscribe(run);
  } else {
    document.addEventListener("DOMContentLoaded", run);
  }
})();
