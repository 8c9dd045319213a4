// penumbra report: sorting, the time budget, chart hover and the comparison viewer.
// Everything it shows was written into the page; this only switches between it.
"use strict";
(function () {
  function sortable(table) {
    var heads = table.querySelectorAll("thead th");
    heads.forEach(function (th, col) {
      th.addEventListener("click", function () {
        var body = table.tBodies[0];
        var rows = Array.prototype.slice.call(body.rows);
        var num = th.getAttribute("data-type") === "num";
        var dir = th.getAttribute("data-dir") === "asc" ? -1 : 1;
        heads.forEach(function (h) { h.removeAttribute("data-dir"); });
        th.setAttribute("data-dir", dir === 1 ? "asc" : "desc");
        function key(row) {
          var cell = row.cells[col];
          var v = cell.getAttribute("data-value");
          if (v === null) { v = cell.textContent; }
          if (num) { var n = parseFloat(v); return isNaN(n) ? Infinity : n; }
          return v;
        }
        rows.sort(function (a, b) {
          var x = key(a), y = key(b);
          return (x < y ? -1 : x > y ? 1 : 0) * dir;
        });
        rows.forEach(function (r) { body.appendChild(r); });
      });
    });
  }
  document.querySelectorAll("table.sortable").forEach(sortable);

  var dataNode = document.getElementById("report-data");
  if (!dataNode) { return; }
  var rows = JSON.parse(dataNode.textContent).rows;
  var selected = document.getElementById("chart-selected");
  var tip = document.getElementById("chart-tip");

  function fmt(v) {
    if (v === null || v === undefined) { return "n/a"; }
    return Math.abs(v) >= 0.01 && Math.abs(v) < 1e4 ? v.toPrecision(3) : v.toExponential(2);
  }

  function highlight(i) {
    document.querySelectorAll(".point.selected, tr.selected").forEach(function (n) {
      n.classList.remove("selected");
    });
    if (i === null) { return; }
    document.querySelectorAll('.point[data-row="' + i + '"], #configs tr[data-row="' + i + '"]')
      .forEach(function (n) { n.classList.add("selected"); });
    if (selected) {
      selected.textContent = "#" + (i + 1) + " " + rows[i].name + ": " + fmt(rows[i].ms) +
        " ms, relative MSE " + fmt(rows[i].rel_mse);
    }
    showInViewer(i);
  }

  function showTip(point) {
    if (!tip) { return; }
    var text = tip.querySelector("text");
    var box = tip.querySelector("rect");
    text.textContent = point.getAttribute("data-summary");
    var shape = point.querySelector("circle:not(.ring), polygon");
    var b = shape.getBBox();
    var svg = point.ownerSVGElement.viewBox.baseVal;
    var w = text.getComputedTextLength() + 12;
    var x = Math.min(b.x + b.width + 6, svg.width - w - 2);
    var y = b.y - 26 < 2 ? b.y + b.height + 4 : b.y - 26;
    text.setAttribute("x", x + 6);
    text.setAttribute("y", y + 15);
    box.setAttribute("x", x);
    box.setAttribute("y", y);
    box.setAttribute("width", w);
    box.setAttribute("height", 21);
    tip.setAttribute("visibility", "visible");
  }

  document.querySelectorAll(".point").forEach(function (p) {
    var i = parseInt(p.getAttribute("data-row"), 10);
    p.addEventListener("mouseenter", function () {
      showTip(p);
      if (selected) { selected.textContent = p.getAttribute("data-summary"); }
    });
    p.addEventListener("mouseleave", function () { if (tip) { tip.setAttribute("visibility", "hidden"); } });
    p.addEventListener("click", function () { highlight(i); });
    p.addEventListener("focus", function () { showTip(p); });
  });
  document.querySelectorAll("#configs tbody tr").forEach(function (tr) {
    tr.addEventListener("click", function () { highlight(parseInt(tr.getAttribute("data-row"), 10)); });
  });

  // The most accurate configuration whose frame time fits the budget.
  function best(budget) {
    var at = null;
    rows.forEach(function (r, i) {
      if (r.ms !== null && r.ms <= budget && r.rel_mse !== null &&
          (at === null || r.rel_mse < rows[at].rel_mse)) { at = i; }
    });
    return at;
  }
  var result = document.getElementById("best-result");
  var budgetInput = document.getElementById("budget-ms");
  function applyBudget(budget) {
    var i = best(budget);
    if (budgetInput) { budgetInput.value = budget; }
    if (i === null) {
      result.textContent = "No configuration runs within " + budget + " ms.";
      highlight(null);
      return;
    }
    highlight(i);
    result.textContent = "Within " + budget + " ms: #" + (i + 1) + " " + rows[i].name + ", " +
      fmt(rows[i].ms) + " ms, relative MSE " + fmt(rows[i].rel_mse) + ".";
  }
  document.querySelectorAll("button.budget").forEach(function (b) {
    b.addEventListener("click", function () { applyBudget(parseFloat(b.getAttribute("data-budget"))); });
  });
  if (budgetInput) {
    budgetInput.addEventListener("change", function () {
      var v = parseFloat(budgetInput.value);
      if (!isNaN(v)) { applyBudget(v); }
    });
  }

  // The comparison viewer: the configuration over the reference, cut by the slider.
  var pick = document.getElementById("viewer-pick");
  var layer = document.getElementById("viewer-layer");
  var slider = document.getElementById("viewer-slider");
  var test = document.getElementById("viewer-test");
  var ref = document.getElementById("viewer-ref");
  var caption = document.getElementById("viewer-caption");
  function cut() { if (test) { test.style.clipPath = "inset(0 " + (100 - slider.value) + "% 0 0)"; } }
  function showInViewer(i) {
    if (!pick) { return; }
    pick.value = String(i);
    var r = rows[i];
    test.src = r[layer.value];
    ref.src = r.reference;
    caption.textContent = "Left: #" + (i + 1) + " " + r.name + " (" + layer.options[layer.selectedIndex].text +
      "); right: the reference.";
  }
  if (pick) {
    pick.addEventListener("change", function () { highlight(parseInt(pick.value, 10)); });
    layer.addEventListener("change", function () { showInViewer(parseInt(pick.value, 10)); });
    slider.addEventListener("input", cut);
    document.getElementById("viewer-flip").addEventListener("click", function () {
      test.style.visibility = test.style.visibility === "hidden" ? "visible" : "hidden";
    });
    cut();
    showInViewer(0);
  }
})();
