// Numbers in table cells stay whole: the browser would break 1.47e-03 after its
// minus sign, so each number in exponent notation (with a " /" after it) is wrapped
// in a span that does not break (the text, and what is copied, stays as written).
(function () {
  "use strict";
  var NUMBER = /[-+]?\d[\d.]*[eE][-+]\d+(?: \/)?/g;

  function wrapNumbers(cell) {
    var walker = document.createTreeWalker(cell, NodeFilter.SHOW_TEXT, null);
    var nodes = [];
    while (walker.nextNode()) {
      if (!walker.currentNode.parentElement.closest("code, .arithmatex, .nobr")) {
        nodes.push(walker.currentNode);
      }
    }
    nodes.forEach(function (node) {
      var text = node.nodeValue;
      NUMBER.lastIndex = 0;
      if (!NUMBER.test(text)) return;
      NUMBER.lastIndex = 0;
      var fragment = document.createDocumentFragment(), last = 0, match;
      while ((match = NUMBER.exec(text)) !== null) {
        fragment.appendChild(document.createTextNode(text.slice(last, match.index)));
        var span = document.createElement("span");
        span.className = "nobr";
        span.textContent = match[0];
        fragment.appendChild(span);
        last = match.index + match[0].length;
      }
      fragment.appendChild(document.createTextNode(text.slice(last)));
      node.parentNode.replaceChild(fragment, node);
    });
  }

  function run() {
    var cells = document.querySelectorAll(".md-typeset table:not([class]) td");
    Array.prototype.forEach.call(cells, wrapNumbers);
  }
  if (typeof document$ !== "undefined") {
    document$.subscribe(run);
  } else {
    document.addEventListener("DOMContentLoaded", run);
  }
})();
