// The page's controller (hht3d.viewer): decodes the fields, colours the one selected,
// keeps the cameras of side-by-side surfaces together and draws the marginal spectrum.
// The state it shows is mirrored on <body data-field data-scale data-ready> for tests.
(function () {
  "use strict";
  var data = JSON.parse(document.getElementById("hht3d-data").textContent);
  var plot = document.getElementById("hht3d-surface");
  var fieldSelect = document.getElementById("hht3d-field");
  var scaleSelect = document.getElementById("hht3d-scale");
  var limitsText = document.getElementById("hht3d-limits");
  var side = document.getElementById("hht3d-side");
  var decoded = {};

  function element(tag, text, className) {
    var node = document.createElement(tag);
    if (text !== undefined) node.textContent = text;
    if (className) node.className = className;
    return node;
  }

  function decode(spec) {
    var binary = atob(spec.bdata);
    var bytes = new Uint8Array(binary.length);
    for (var i = 0; i < binary.length; i++) bytes[i] = binary.charCodeAt(i);
    return new Float32Array(bytes.buffer);
  }

  function values(field, copy) {
    var key = field.name + "/" + copy;
    if (!decoded[key]) decoded[key] = decode(field.values[copy]);
    return decoded[key];
  }

  function fieldByName(name) {
    for (var i = 0; i < data.fields.length; i++) if (data.fields[i].name === name) return data.fields[i];
    return null;
  }

  function number(x) {
    return Math.abs(x) >= 1e4 || (x !== 0 && Math.abs(x) < 1e-3) ? x.toExponential(3) : x.toPrecision(4);
  }

  // -- header, selector, side panel --------------------------------------------------------
  document.getElementById("hht3d-title").textContent = data.title;
  document.getElementById("hht3d-size").textContent = data.size;
  data.notices.forEach(function (text) {
    document.getElementById("hht3d-notices").appendChild(element("p", text, "notice"));
  });
  var groups = {};
  fieldSelect.appendChild(new Option("shape (no field)", data.shape));
  data.fields.forEach(function (field) {
    if (!groups[field.group]) {
      groups[field.group] = document.createElement("optgroup");
      groups[field.group].label = field.group;
      fieldSelect.appendChild(groups[field.group]);
    }
    groups[field.group].appendChild(new Option(field.label, field.name));
  });
  fieldSelect.value = data.initial;

  if (data.spectrum) {
    side.appendChild(element("h2", "Marginal Hilbert spectrum"));
    var spectrumDiv = element("div");
    spectrumDiv.id = "hht3d-spectrum";
    side.appendChild(spectrumDiv);
    side.appendChild(element("p", data.spectrum.caption));
  }
  if (data.quality) {
    side.appendChild(element("h2", "Decomposition quality"));
    var table = element("table");
    data.quality.rows.forEach(function (row) {
      var tr = element("tr");
      tr.appendChild(element("th", row[0]));
      tr.appendChild(element("td", row[1], row[2] ? "num bad" : "num"));
      table.appendChild(tr);
    });
    side.appendChild(table);
    if (data.quality.warnings.length) {
      var list = element("ul", undefined, "warnings");
      data.quality.warnings.forEach(function (w) { list.appendChild(element("li", w)); });
      side.appendChild(list);
    }
  }

  // -- the spectrum plot ---------------------------------------------------------------------
  function spectrumTraces(highlight) {
    var s = data.spectrum;
    var traces = [{
      type: "scatter", mode: "lines", line: {shape: "hv", color: "#1f3f73", width: 2},
      fill: "tozeroy", fillcolor: "rgba(76,114,176,0.25)", name: "all IMFs",
      x: s.edges, y: s.marginal.concat([s.marginal[s.marginal.length - 1]]),
      hovertemplate: "ω %{x:.3g}: %{y:.3g}%<extra>all IMFs</extra>"
    }];
    s.imfs.forEach(function (share, k) {
      traces.push({
        type: "scatter", mode: "lines", line: {shape: "hv", width: highlight === k + 1 ? 3 : 1},
        opacity: highlight && highlight !== k + 1 ? 0.35 : 0.9, name: "IMF " + (k + 1),
        x: s.edges, y: share.concat([share[share.length - 1]]),
        hovertemplate: "ω %{x:.3g}: %{y:.3g}%<extra>IMF " + (k + 1) + "</extra>"
      });
    });
    return traces;
  }

  function spectrumLayout(band) {
    var s = data.spectrum;
    var shapes = [], annotations = [];
    if (band) {
      shapes.push({type: "rect", xref: "x", yref: "paper", x0: band[0], x1: band[1], y0: 0, y1: 1,
                   fillcolor: "rgba(255,170,0,0.15)", line: {width: 0}, layer: "below"});
    }
    if (s.resolvable_frequency !== null) {
      shapes.push({type: "line", xref: "x", yref: "paper", x0: s.resolvable_frequency, x1: s.resolvable_frequency,
                   y0: 0, y1: 1, line: {color: "#b00020", dash: "dash", width: 1.5}});
      // annotations on a log axis take log10 of the value (shapes take the value itself)
      var at = s.scale === "log" ? Math.log10(s.resolvable_frequency) : s.resolvable_frequency;
      annotations.push({xref: "x", yref: "paper", x: at, y: 1, yanchor: "bottom",
                        text: "resolution limit", showarrow: false, font: {color: "#b00020", size: 11}});
    }
    return {
      margin: {l: 48, r: 8, t: 16, b: 40}, showlegend: true, legend: {font: {size: 10}},
      xaxis: {type: s.scale, title: {text: "instantaneous frequency ω (rad / unit)"}},
      yaxis: {title: {text: "share of energy per bin (%)"}, rangemode: "tozero"},
      shapes: shapes, annotations: annotations
    };
  }

  // -- the surfaces --------------------------------------------------------------------------
  function scaleOf(field) {
    return scaleSelect.value === "auto" ? field.auto : scaleSelect.value;
  }

  function surfaceTraces(name) {
    var field = fieldByName(name);
    return data.figure.data.map(function (base, index) {
      var trace = Object.assign({}, base);
      var surface = data.surfaces[index];
      if (!field) {
        if (surface.points) trace.marker = Object.assign({}, base.marker, {color: data.shape_color});
        else trace.color = data.shape_color;
        return trace;
      }
      var scale = scaleOf(field);
      var limits = field[scale];
      var colour = {cmin: limits[0], cmax: limits[1], colorscale: data.colorscales[scale],
                    showscale: index === data.figure.data.length - 1,
                    colorbar: {title: {text: field.title}, len: 0.8}};
      if (surface.points) {
        trace.marker = Object.assign({}, base.marker, colour, {color: values(field, surface.copy)});
      } else {
        Object.assign(trace, colour, {intensity: values(field, surface.copy)});
      }
      trace.hovertemplate = field.title + " %{" + (surface.points ? "marker.color" : "intensity") +
        ":.4g}<extra>" + surface.label + "</extra>";
      return trace;
    });
  }

  function describeLimits(field) {
    if (!field) return "";
    var scale = scaleOf(field), lim = field[scale];
    var low = "p" + data.percentiles[0], high = "p" + data.percentiles[1];
    var how = scale === "symmetric" ? "±max(|" + low + "|, |" + high + "|)" : low + " to " + high;
    return "colour limits " + number(lim[0]) + " … " + number(lim[1]) + " (" + how + ")";
  }

  var syncing = false;
  function shareCamera(event) {
    if (syncing) return;
    var scenes = Object.keys(event).filter(function (k) { return /^scene\d*\.camera$/.test(k); });
    if (!scenes.length) return;
    var camera = event[scenes[0]], update = {};
    data.figure.data.forEach(function (trace) {
      var key = trace.scene + ".camera";
      if (key !== scenes[0]) update[key] = camera;
    });
    if (!Object.keys(update).length) return;
    syncing = true;
    Plotly.relayout(plot, update).then(function () { syncing = false; });
  }

  function show() {
    var name = fieldSelect.value, field = fieldByName(name);
    limitsText.textContent = describeLimits(field);
    var drawn = [Plotly.react(plot, surfaceTraces(name), data.figure.layout, data.config)];
    if (data.spectrum) {
      var imf = /^frequency_(\d+)$/.exec(name);
      var band = imf ? field[scaleOf(field)] : null;
      drawn.push(Plotly.react("hht3d-spectrum", spectrumTraces(imf ? Number(imf[1]) : 0),
                              spectrumLayout(band), data.config));
    }
    return Promise.all(drawn).then(function () {
      document.body.dataset.field = name;
      document.body.dataset.scale = field ? scaleOf(field) : "";
    });
  }

  fieldSelect.addEventListener("change", show);
  scaleSelect.addEventListener("change", show);
  show().then(function () {
    plot.on("plotly_relayout", shareCamera);
    document.body.dataset.ready = "true";
  });
})();
