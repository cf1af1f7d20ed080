// Sorts a table of class "racf-sortable" by the column whose head is clicked (or given Enter):
// by each cell's data-sort (a number where it parses as one, else text), best-first on the first
// click where the column is a rate; cells with no value go last either way.
(function () {
  function key(cell) {
    const raw = cell.dataset.sort !== undefined ? cell.dataset.sort : cell.textContent.trim();
    const num = parseFloat(raw);
    return raw === "" ? null : (isNaN(num) ? raw.toLowerCase() : num);
  }
  function sortBy(th) {
    const table = th.closest("table");
    const column = Array.prototype.indexOf.call(th.parentNode.children, th);
    const descending = th.getAttribute("aria-sort") !== "descending";
    const body = table.tBodies[0];
    const rows = Array.from(body.rows);
    rows.sort(function (a, b) {
      const x = key(a.cells[column]), y = key(b.cells[column]);
      if (x === null || y === null) return (x === null) - (y === null);
      const order = x < y ? -1 : x > y ? 1 : 0;
      return descending ? -order : order;
    });
    rows.forEach(function (row) { body.appendChild(row); });
    table.querySelectorAll("th").forEach(function (h) { h.removeAttribute("aria-sort"); });
    th.setAttribute("aria-sort", descending ? "descending" : "ascending");
  }
  function wire() {
    document.querySelectorAll("table.racf-sortable th").forEach(function (th) {
      if (th.dataset.wired) return;
      th.dataset.wired = "1";
      th.tabIndex = 0;
      th.addEventListener("click", function () { sortBy(th); });
      th.addEventListener("keydown", function (e) { if (e.key === "Enter") sortBy(th); });
    });
  }
  if (document.readyState === "loading") document.addEventListener("DOMContentLoaded", wire); else wire();
})();
