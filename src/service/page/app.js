// windmeta's page: a client of the public API like any other. Every action is an API call; long
// work (calibrations, validations, analyses) goes through operations whose progress arrives on the
// event stream, so nothing on the page waits on a long request.
// The page's one entry point: the modules it needs are imported here, and the browser loads the
// rest through them.
import { drawExceedance, explore, fragility, hazard, sensitivity, setUpAnalysisForms } from './analyses.js';
import { $, session, setUpKey } from './client.js';
import { serviceability, sweep } from './design.js';
import { calibrate, deleteMetamodel, loadMetamodels, loadPresets, showPreset, validate } from './metamodels.js';
import { loadOperations } from './operations.js';

/** Loads a list, its failure shown in the list's own error line (cleared by a success); whether it loaded. */
async function reload(list, load) {
  const error = $(`#${list}-error`);
  try {
    await load();
    error.textContent = '';
    return true;
  } catch (failure) {
    error.textContent = failure.message;
    return false;
  }
}

/** The presets, operations and metamodels, stopping at the first failure (a missing key, as a rule). */
async function loadEverything() {
  (await reload('calibration', loadPresets)) && (await reload('operations', loadOperations)) && (await reload('metamodels', loadMetamodels));
}

function start() {
  setUpKey(loadEverything);
  setUpAnalysisForms();
  $('#calibration-preset').addEventListener('change', showPreset);
  $('#calibration-form').addEventListener('submit', calibrate);
  $('#operations-refresh').addEventListener('click', () => reload('operations', loadOperations));
  $('#metamodels-refresh').addEventListener('click', () => reload('metamodels', loadMetamodels));
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
  $('#serviceability-form').addEventListener('submit', serviceability);
  $('#sweep-form').addEventListener('submit', sweep);
  $('#fragility-form').addEventListener('submit', fragility);
  $('#sensitivity-form').addEventListener('submit', sensitivity);
  loadEverything();
}

start();
