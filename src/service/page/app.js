// windmeta's page: a client of the public API like any other. Every action is an API call; long
// work (calibrations, validations, analyses) goes through operations whose progress arrives on the
// event stream, so nothing on the page waits on a long request.
'use strict';

async function loadEverything() {
  try {
    await loadPresets();
    await loadOperations();
    await loadMetamodels();
  } catch (error) {
    $('#calibration-error').textContent = error.message;
  }
}

function start() {
  setUpKey();
  setUpAnalysisForms();
  $('#calibration-preset').addEventListener('change', showPreset);
  $('#calibration-form').addEventListener('submit', calibrate);
  $('#operations-refresh').addEventListener('click', () => loadOperations().catch((e) => { $('#calibration-error').textContent = e.message; }));
  $('#metamodels-refresh').addEventListener('click', () => loadMetamodels().catch((e) => { $('#calibration-error').textContent = e.message; }));
  $('#validation-form').addEventListener('submit', validate);
  $('#metamodel-delete').addEventListener('click', deleteMetamodel);
  $('#explore-form').addEventListener('submit', explore);
  $('#explore-hold-wind').addEventListener('change', (event) => { $('#explore-wind').disabled = !event.target.checked; });
  $('#explore-wind').addEventListener('input', (event) => { $('#explore-wind-value').textContent = event.target.value; });
  $('#explore-keep').addEventListener('click', () => {
    session.curves.kept = session.curves.latest;
    $('#explore-clear').hidden = false;
    drawExceedance();
  });
  $('#explore-clear').addEventListener('click', () => {
    session.curves.kept = null;
    $('#explore-clear').hidden = true;
    drawExceedance();
  });
  $('#hazard-form').addEventListener('submit', hazard);
  $('#fragility-form').addEventListener('submit', fragility);
  $('#sensitivity-form').addEventListener('submit', sensitivity);
  loadEverything();
}

start();
