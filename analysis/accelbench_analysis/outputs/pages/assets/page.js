// The analysis's HTML pages: sortable, filterable tables and Vega-Lite figures. Runs from
// file:// with no network; vegaEmbed comes from the bundle inlined before this script.
(function () {
  "use strict";

  // ---- tables ------------------------------------------------------------------------------

  // The number a cell starts with ("0.107 [0.10, 0.11]", "1,683,281", "2.43x", "-0.531 s"),
  // or null when it starts with text ("—" and empty cells included).
  var NUMBER = /^\s*([-+\u2212]?)(\d[\d,]*(?:\.\d+)?|\.\d+)(?:e([-+]?\d+))?/i;
  function leadingNumber(text) {
    var m = NUMBER.exec(text);
    if (!m) return null;
    var v = parseFloat(m[2].replace(/,/g, "") + (m[3] ? "e" + m[3] : ""));
    return m[1] === "-" || m[1] === "\u2212" ? -v : v;
  }

  var collator = new Intl.Collator(undefined, { numeric: true, sensitivity: "base" });

  // Rows sort within their tbody: a table with section rows ("Build time (s)") has one tbody
  // per section, and the section's label row stays first.
  function sortTable(table, col, descending) {
    var bodies = table.tBodies;
    var numeric = columnIsNumeric(table, col);
    for (var b = 0; b < bodies.length; b++) {
      var rows = Array.prototype.filter.call(bodies[b].rows, function (r) {
        return !r.classList.contains("section");
      });
      var keyed = rows.map(function (r, i) {
        var cell = r.cells[col];
        var text = cell ? cell.textContent.trim() : "";
        return { row: r, text: text, num: numeric ? leadingNumber(text) : null, i: i };
      });
      keyed.sort(function (a, b) {
        var c;
        if (numeric) {
          if (a.num === null && b.num === null) c = 0;
          else if (a.num === null) return 1; // no number: last in both directions
          else if (b.num === null) return -1;
          else c = a.num - b.num;
        } else {
          c = 0;
        }
        if (c === 0) c = collator.compare(a.text, b.text);
        if (c === 0) c = a.i - b.i;
        return descending ? -c : c;
      });
      keyed.forEach(function (k) {
        bodies[b].appendChild(k.row);
      });
    }
  }

  function columnIsNumeric(table, col) {
    var withNumber = 0, withText = 0;
    Array.prototype.forEach.call(table.tBodies, function (body) {
      Array.prototype.forEach.call(body.rows, function (r) {
        if (r.classList.contains("section") || !r.cells[col]) return;
        var t = r.cells[col].textContent.trim();
        if (t === "" || t === "\u2014" || t === "-" || t === "\u2013") return;
        if (leadingNumber(t) === null) withText++;
        else withNumber++;
      });
    });
    return withNumber > 0 && withNumber >= withText;
  }

  function makeSortable(table) {
    var head = table.tHead;
    if (!head || !head.rows.length) return;
    var cells = head.rows[head.rows.length - 1].cells;
    Array.prototype.forEach.call(cells, function (th, col) {
      th.title = "Sort by this column";
      th.addEventListener("click", function () {
        var descending = th.getAttribute("aria-sort") === "ascending";
        Array.prototype.forEach.call(cells, function (other) {
          other.removeAttribute("aria-sort");
        });
        th.setAttribute("aria-sort", descending ? "descending" : "ascending");
        sortTable(table, col, descending);
      });
    });
  }

  // A row stays when every word of the filter occurs in its text; a section row stays
  // while any row of its section does.
  function filterTable(table, query, counter) {
    var words = query.toLowerCase().split(/\s+/).filter(Boolean);
    var shown = 0, total = 0;
    Array.prototype.forEach.call(table.tBodies, function (body) {
      var any = false, section = null;
      Array.prototype.forEach.call(body.rows, function (r) {
        if (r.classList.contains("section")) {
          section = r;
          return;
        }
        var text = r.textContent.toLowerCase();
        var keep = words.every(function (w) {
          return text.indexOf(w) >= 0;
        });
        r.hidden = !keep;
        total++;
        if (keep) {
          shown++;
          any = true;
        }
      });
      if (section) section.hidden = !any;
    });
    counter.textContent = words.length ? shown + " of " + total + " rows" : total + " rows";
  }

  function addFilter(table) {
    var wrap = table.closest(".table-wrap") || table;
    var tools = document.createElement("div");
    tools.className = "table-tools";
    var input = document.createElement("input");
    input.type = "search";
    input.placeholder = "Filter rows (all words must match)";
    input.setAttribute("aria-label", "Filter the rows of this table");
    var counter = document.createElement("span");
    tools.appendChild(input);
    tools.appendChild(counter);
    wrap.parentNode.insertBefore(tools, wrap);
    input.addEventListener("input", function () {
      filterTable(table, input.value, counter);
    });
    filterTable(table, "", counter);
    table.filterBy = function (q) {
      input.value = q;
      filterTable(table, q, counter);
    };
  }

  // ---- figures -----------------------------------------------------------------------------

  var views = [];

  function drawCharts() {
    var targets = Array.prototype.slice.call(document.querySelectorAll("div.vega"));
    if (!targets.length) return Promise.resolve();
    if (typeof window.vegaEmbed !== "function") {
      return Promise.reject(new Error("vegaEmbed is missing: the page was written without its bundle"));
    }
    return Promise.all(
      targets.map(function (el) {
        var spec = JSON.parse(el.nextElementSibling.textContent);
        var options = {
          renderer: "svg",
          actions: { export: true, source: false, compiled: false, editor: false },
        };
        return window.vegaEmbed(el, spec, options).then(function (result) {
          views.push(result.view);
          el.setAttribute("data-drawn", "true");
        }, function (err) {
          const p = document.createElement("p");  // the message as text: it may quote data
          p.className = "chart-error";
          p.textContent = "This figure could not be drawn: " + String(err && err.message || err);
          el.replaceChildren(p);
          throw err;
        });
      })
    );
  }

  // An element with data-panel="VALUE" shows that panel in every figure that has a
  // `panel` parameter (the history page's table of structures and models).
  function selectPanel(value) {
    views.forEach(function (view) {
      try {
        view.signal("panel", value).runAsync();
      } catch (e) {
        // this view has no panel parameter
      }
    });
  }

  document.addEventListener("click", function (ev) {
    var el = ev.target.closest("[data-panel]");
    if (!el) return;
    ev.preventDefault();
    selectPanel(el.getAttribute("data-panel"));
    var target = document.getElementById(el.getAttribute("data-panel-target") || "panel-figures");
    if (target) target.scrollIntoView({ behavior: "auto", block: "start" });
  });

  // A table of at most this many rows is read whole: it sorts, but gets no filter box (the
  // box would take a line of the first screen for nothing).
  var SHOWN_WHOLE = 10;

  function bodyRows(table) {
    var n = 0;
    Array.prototype.forEach.call(table.tBodies, function (body) {
      Array.prototype.forEach.call(body.rows, function (r) {
        if (!r.classList.contains("section")) n++;
      });
    });
    return n;
  }

  function start() {
    Array.prototype.forEach.call(document.querySelectorAll("table.data"), function (t) {
      makeSortable(t);
      if (bodyRows(t) > SHOWN_WHOLE) addFilter(t);
    });
    drawCharts().then(
      function () {
        document.documentElement.setAttribute("data-charts", "ready");
      },
      function (err) {
        document.documentElement.setAttribute("data-charts", "failed");
        console.error("figure failed: " + (err && err.message || err));
      }
    );
  }

  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", start);
  else start();
})();
