// The bathyslam page: sign in with an API token, see the tenant's surveys and jobs with live
// progress, open a job's quality report and map. Everything comes from the HTTP API
// (docs/http.md) with the token as `Authorization: Bearer`; that header is why tiles, plots,
// downloads and progress are fetched by hand rather than by <img>, <a> or EventSource.
"use strict";

const state = { token: sessionStorage.getItem("bathyslam-token") || "", openJob: null, streams: new Map(), refresh: 0 };
const $ = (id) => document.getElementById(id);

function headers() {
  return state.token ? { Authorization: "Bearer " + state.token } : {};
}

async function api(path) {
  const response = await fetch(path, { headers: headers() });
  if (!response.ok) {
    let message = response.statusText;
    try { message = (await response.json()).error; } catch (ignored) {}
    throw new Error(`${path}: ${response.status} ${message}`);
  }
  return response;
}
const json = async (path) => (await api(path)).json();
const blobUrl = async (path) => URL.createObjectURL(await (await api(path)).blob());

function showError(error) {
  $("error").textContent = error ? String(error.message || error) : "";
}

function cell(row, content) {
  const td = row.insertCell();
  if (content instanceof Node) td.append(content); else td.textContent = content;
  return td;
}

// Lists

async function signIn() {
  showError("");
  try {
    const surveys = (await json("/v1/surveys?page_size=1000")).surveys;
    const jobs = (await json("/v1/jobs?page_size=1000")).jobs;
    sessionStorage.setItem("bathyslam-token", state.token);
    $("who").textContent = `signed in: ${surveys.length} surveys, ${jobs.length} jobs`;
    renderSurveys(surveys);
    renderJobs(jobs);
    document.body.dataset.signedIn = "true";
  } catch (error) {
    showError(error);
  }
}

function renderSurveys(surveys) {
  const body = $("surveys").tBodies[0];
  body.replaceChildren();
  for (const s of surveys) {
    const row = body.insertRow();
    row.dataset.survey = s.id;
    [s.id, s.name, s.crs, s.ready ? "yes" : "no"].forEach((v) => cell(row, v));
  }
}

const active = (job) => job.state === "queued" || job.state === "running";

// The list is read again every few seconds while a job is active; only the open job has a stream
// of its own (a browser keeps six connections to a server, and a stream holds one).
function renderJobs(jobs) {
  const body = $("jobs").tBodies[0];
  body.replaceChildren();
  for (const job of jobs) {
    const row = body.insertRow();
    row.id = `job-row-${job.id}`;
    updateJobRow(row, job);
  }
  clearTimeout(state.refresh);
  if (jobs.some(active)) state.refresh = setTimeout(refreshJobs, 5000);
}

async function refreshJobs() {
  try {
    renderJobs((await json("/v1/jobs?page_size=1000")).jobs);
  } catch (error) {
    showError(error);
  }
}

function updateJobRow(row, job) {
  row.replaceChildren();
  row.dataset.state = job.state;
  const bar = Object.assign(document.createElement("progress"), { max: 1, value: job.progress || 0 });
  const open = Object.assign(document.createElement("button"), { textContent: "open" });
  open.onclick = () => openJob(job.id);
  [job.id, job.survey_id, job.configuration, `${job.state}${job.stage ? " · " + job.stage : ""}`, bar, open]
    .forEach((v) => cell(row, v));
  row.classList.toggle("selected", state.openJob === job.id);
}

// Server-sent events read from a fetch body: EventSource cannot send the token.
async function followProgress(jobId) {
  if (state.streams.has(jobId)) return;
  state.streams.set(jobId, true);
  try {
    const reader = (await api(`/v1/jobs/${jobId}/events`)).body.pipeThrough(new TextDecoderStream()).getReader();
    let buffer = "";
    for (;;) {
      const { value, done } = await reader.read();
      if (done) break;
      buffer += value;
      let end;
      while ((end = buffer.indexOf("\n\n")) >= 0) {
        onEvent(jobId, buffer.slice(0, end));
        buffer = buffer.slice(end + 2);
      }
    }
  } catch (error) {
    showError(error);
  } finally {
    state.streams.delete(jobId);
  }
}

function onEvent(jobId, text) {
  const fields = {};
  for (const line of text.split("\n")) {
    if (!line || line.startsWith(":")) continue;
    const colon = line.indexOf(": ");
    fields[line.slice(0, colon)] = line.slice(colon + 2);
  }
  if (!fields.event) return;
  const data = JSON.parse(fields.data);
  const row = $(`job-row-${jobId}`);
  if (fields.event === "progress" && row) {
    row.cells[3].textContent = `running · ${data.stage}`;
    row.cells[4].firstChild.value = data.progress;
  } else if (fields.event === "end") {
    if (row) updateJobRow(row, data);
    if (state.openJob === jobId) openJob(jobId);
    refreshJobs();
  }
}

// A job

async function openJob(jobId) {
  state.openJob = jobId;
  showError("");
  for (const row of $("jobs").tBodies[0].rows) row.classList.toggle("selected", row.id === `job-row-${jobId}`);
  const job = await json(`/v1/jobs/${jobId}`);
  $("job").hidden = false;
  $("job-title").textContent = `Job ${job.id}: ${job.configuration} on survey ${job.survey_id}, ${job.state}`;
  document.body.dataset.jobState = job.state;
  if (job.state !== "succeeded") {
    $("report").textContent = job.state === "failed" ? `failed: ${job.error}` : "waiting for the job to finish";
    if (active(job)) followProgress(jobId);
    return;
  }
  try {
    await Promise.all([showReport(jobId), showMap(jobId)]);
    showDownloads(jobId);
  } catch (error) {
    showError(error);
  }
}

function statsTable(title, figures) {
  const table = document.createElement("table");
  table.createCaption().textContent = title;
  const head = table.createTHead().insertRow();
  ["", "RMSE (m)", "p99 (m)"].forEach((h) => head.append(Object.assign(document.createElement("th"), { textContent: h })));
  for (const [name, s] of figures) {
    if (!s) continue;
    const row = table.insertRow();
    [name, s.rmse.toFixed(3), s.p99.toFixed(3)].forEach((v) => cell(row, v));
  }
  return table;
}

async function showReport(jobId) {
  const report = await json(`/v1/jobs/${jobId}/report.json`);
  const box = $("report");
  box.replaceChildren();
  const c = report.consistency_error_m || {}, t = report.trajectory_error_m || {};
  box.append(statsTable("Consistency of overlapping soundings", [["corrected", c.optimized], ["dead reckoning", c.dead_reckoning]]));
  if (t.optimized && t.optimized.count > 0)
    box.append(statsTable("Trajectory against the reference", [["corrected", t.optimized], ["dead reckoning", t.dead_reckoning]]));
  if (report.safety_net && report.safety_net.verdict)
    box.append(Object.assign(document.createElement("p"), { textContent: "Safety net: " + report.safety_net.verdict }));
  for (const name of ["map.png", "trajectory.png", "consistency_histogram.png", "trajectory_error.png", "map_difference.png"]) {
    try {
      box.append(Object.assign(document.createElement("img"), { src: await blobUrl(`/v1/jobs/${jobId}/plots/${name}`), alt: name }));
    } catch (missing) {}  // a job has the plots its data allow
  }
  box.dataset.loaded = "true";
}

// Tiles fetched with the token, shown from blob URLs.
const AuthorisedTiles = L.TileLayer.extend({
  createTile(coords, done) {
    const tile = document.createElement("img");
    tile.alt = "";
    api(this.getTileUrl(coords)).then((r) => r.blob()).then((blob) => {
      tile.onload = () => { URL.revokeObjectURL(tile.src); done(null, tile); };  // drawn: the bytes can go
      tile.src = URL.createObjectURL(blob);
    }).catch((error) => done(error, tile));
    return tile;
  },
});

let map = null;
async function showMap(jobId) {
  const tilejson = await json(`/v1/jobs/${jobId}/tiles.json`);
  const [west, south, east, north] = tilejson.bounds;
  if (map) map.remove();
  map = L.map("map", { maxZoom: tilejson.maxzoom });
  document.body.dataset.tilesLoaded = "false";
  const tiles = new AuthorisedTiles(`/v1/jobs/${jobId}/tiles/{z}/{x}/{y}.png`, {
    maxZoom: tilejson.maxzoom, maxNativeZoom: tilejson.maxzoom, bounds: [[south, west], [north, east]],
    attribution: `bathyslam job ${jobId}`,
  });
  tiles.on("load", () => { document.body.dataset.tilesLoaded = "true"; });
  tiles.addTo(map);
  map.fitBounds([[south, west], [north, east]]);
  const styles = { dead_reckoning: { color: "#888", weight: 2, dashArray: "4 4" }, corrected: { color: "#d62828", weight: 2 },
                   loop_closure: { color: "#1d70b8", weight: 1 } };
  const tracks = await json(`/v1/jobs/${jobId}/trajectory.geojson`);
  L.geoJSON(tracks, { style: (f) => styles[f.properties.kind] }).addTo(map);
  $("map").dataset.loops = tracks.features.filter((f) => f.properties.kind === "loop_closure").length;
}

function showDownloads(jobId) {
  const box = $("downloads");
  box.replaceChildren();
  for (const [file, label] of [["map.tif", "map (COG)"], ["map.bag", "BAG"], ["corrected.gsf", "corrected GSF"], ["report.json", "report"]]) {
    const link = Object.assign(document.createElement("a"), { href: "#", textContent: label });
    link.onclick = async (event) => {
      event.preventDefault();
      try {
        const a = Object.assign(document.createElement("a"), { href: await blobUrl(`/v1/jobs/${jobId}/${file}`), download: `job-${jobId}-${file}` });
        a.click();
      } catch (error) {
        showError(error);
      }
    };
    box.append(link);
  }
}

// Start: a token and a job may come in the address (#token=...&job=N) for links and tests.
$("sign-in").onsubmit = (event) => {
  event.preventDefault();
  state.token = $("token").value.trim();
  signIn();
};
const given = new URLSearchParams(location.hash.slice(1));
if (given.has("token")) state.token = given.get("token");
$("token").value = state.token;
signIn().then(() => { if (given.has("job")) openJob(Number(given.get("job"))); });
