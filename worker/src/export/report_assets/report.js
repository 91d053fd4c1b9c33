// The run report's page script (worker/src/export/report_assets/report.js, compiled in).
// A classic script, loaded last: it needs no network and no module loading, so the page
// works opened from file://.
//
// - Stage timings: timings.js (written beside index.html, not deterministic) assigns
//   window.csgtileTimings = {stages: [[name, seconds], ...], peak: {job, mib}}; the stages
//   drawn here as a bar chart, the job of the highest peak memory named under it.
// - 3D view: viewer.js defines window.csgtileViewer (absent when csgtile was built without
//   it). A cell's GLB comes as base64 from cells/<id>.glb.js, loaded by a <script> element
//   when the cell is chosen (Chromium refuses fetch() of file:// URLs).
// - document.body.dataset.viewer tells tests where the 3D view is: "loading", "ready",
//   "unavailable" (no viewer or no cell with a GLB) or "error".
(function () {
  'use strict';
  var svgNamespace = 'http://www.w3.org/2000/svg';

  function element(namespace, name, attributes, text) {
    var node = namespace ? document.createElementNS(namespace, name) : document.createElement(name);
    Object.keys(attributes || {}).forEach(function (key) { node.setAttribute(key, attributes[key]); });
    if (text !== undefined) node.textContent = text;
    return node;
  }

  function drawTimings() {
    var target = document.getElementById('timings');
    if (!target) return;
    var stages = (window.csgtileTimings && window.csgtileTimings.stages) || [];
    target.textContent = '';
    if (stages.length === 0) {
      target.appendChild(element(null, 'p', {class: 'note'}, 'No stage timings recorded.'));
      return;
    }
    var longest = stages.reduce(function (m, s) { return Math.max(m, s[1]); }, 0) || 1;
    var rowHeight = 22, labelWidth = 180, barWidth = 520;
    var svg = element(svgNamespace, 'svg', {
      width: labelWidth + barWidth + 90, height: stages.length * rowHeight + 8,
      role: 'img', 'aria-label': 'stage timings'});
    stages.forEach(function (stage, i) {
      var y = i * rowHeight + 4;
      svg.appendChild(element(svgNamespace, 'text', {x: labelWidth - 8, y: y + 14, 'text-anchor': 'end'}, stage[0]));
      svg.appendChild(element(svgNamespace, 'rect', {
        class: 'bar time', x: labelWidth, y: y + 2, height: rowHeight - 6,
        width: Math.max(1, (stage[1] / longest) * barWidth)}));
      svg.appendChild(element(svgNamespace, 'text', {
        x: labelWidth + (stage[1] / longest) * barWidth + 6, y: y + 14}, stage[1].toFixed(3) + ' s'));
    });
    target.appendChild(svg);
    var peak = window.csgtileTimings.peak;
    if (peak) {
      target.appendChild(element(null, 'p', {class: 'note'},
          'Highest peak memory of a job: ' + peak.mib.toFixed(1) + ' MiB (' + peak.job + ')'));
    }
  }

  var view = null;
  var loaded = {};

  function setState(state, message) {
    document.body.dataset.viewer = state;
    var status = document.getElementById('viewer-status');
    if (status && message !== undefined) status.textContent = message;
  }

  // Resolves with the cell's base64 GLB, loading its script once.
  function cellGlb(id, script) {
    if (loaded[id]) return loaded[id];
    loaded[id] = new Promise(function (resolve, reject) {
      var tag = element(null, 'script', {src: script});
      tag.onload = function () {
        var glb = window.csgtileGlb && window.csgtileGlb[id];
        if (glb) resolve(glb); else reject(new Error(script + ' defines no GLB for cell ' + id));
      };
      tag.onerror = function () { reject(new Error('cannot load ' + script)); };
      document.head.appendChild(tag);
    });
    return loaded[id];
  }

  function showCell(id) {
    var select = document.getElementById('cell-select');
    var option = select && select.querySelector('option[value="' + id + '"]');
    document.querySelectorAll('svg .cell').forEach(function (rect) {
      rect.classList.toggle('selected', rect.dataset.cell === id);
    });
    if (!option) return;
    select.value = id;
    var script = option.dataset.glbScript;
    if (!script) {
      setState('unavailable', 'Cell ' + id + ': ' + (option.dataset.reason || 'no glTF'));
      return;
    }
    if (!view) return;
    setState('loading', 'Cell ' + id + ': loading\u2026');
    cellGlb(id, script)
      .then(function (glb) { return view.show(glb); })
      .then(function () {
        setState('ready', 'Cell ' + id + ': drag to orbit, wheel to zoom, right-drag to pan.');
      })
      .catch(function (error) {
        setState('error', 'Cell ' + id + ': ' + error.message);
        console.error('csgtile report: cell ' + id + ': ' + error.message);
      });
  }

  function setUpViewer() {
    var select = document.getElementById('cell-select');
    var container = document.getElementById('viewer');
    if (!select || !container) return;
    if (!window.csgtileViewer) {
      setState('unavailable');
      return;
    }
    var first = select.querySelector('option[data-glb-script]');
    if (!first) {
      setState('unavailable', 'No cell has a glTF to show.');
      return;
    }
    try {
      view = window.csgtileViewer.create(container);
    } catch (error) {
      setState('error', '3D view unavailable: ' + error.message);
      console.error('csgtile report: ' + error.message);
      return;
    }
    select.addEventListener('change', function () { showCell(select.value); });
    document.querySelectorAll('svg .cell').forEach(function (rect) {
      rect.addEventListener('click', function () {
        showCell(rect.dataset.cell);
        container.scrollIntoView({behavior: 'smooth', block: 'center'});
      });
    });
    showCell(first.value);
  }

  drawTimings();
  setUpViewer();
})();
