//! `surfcap.AppearanceModel`: eigen appearance maps (thesis chapter 4), as `surfcap appearance
//! build | reconstruct | interpolate | complete`. `build` aligns per-frame texture maps to a
//! reference chosen by medoid shift (TV-L1 flows, Poisson warping) and keeps eigen textures and
//! eigen warps; `reconstruct`, `interpolate` and `complete` give `(H, W, 3)` uint8 maps, the
//! bytes the command writes into its PNG.
//!
//! The inputs are turned into the model's by the command's own helpers
//! (`surfcap_appearance::appearance_requests`): the same checks, messages and numbers. Flows go
//! through the derived cache, in the same folder and under the same keys as the command's.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use numpy::{PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyIndexError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use surfcap_appearance::appearance_requests as req;
use surfcap_appearance::texture_folder::{frame_name, read_textures};
use surfcap_appearance::{
    AppearanceModel, AppearanceOptions, TexelMask, TextureImage, Warping, build_appearance_model,
};
use surfcap_mesh::{Subject, Topology};

use crate::errors::IntoPyResult;
use crate::progress::PyProgress;
use crate::subject::{CacheChoice, PySubject};

/// An appearance model: built from maps, or read from a folder `surfcap appearance build`
/// wrote.
#[pyclass(frozen, name = "AppearanceModel", module = "surfcap")]
pub struct PyAppearanceModel {
    model: Arc<AppearanceModel>,
    /// The build's summary (`surfcap appearance build --json`), when built here.
    report: Option<String>,
    /// Where flows are cached (`complete`).
    cache: CacheChoice,
}

/// Texture maps `(F, H, W, 3)` uint8 as images.
fn maps_of_array(a: &Bound<'_, PyAny>) -> PyResult<Vec<TextureImage>> {
    let arr = a
        .cast::<PyArrayDyn<u8>>()
        .map_err(|_| PyTypeError::new_err("maps: expected a folder or an (F, H, W, 3) uint8 array"))?;
    let shape = arr.shape().to_vec();
    let [f, h, w, 3] = shape[..] else {
        return Err(PyValueError::new_err(format!("maps: shape {shape:?}, expected (frames, height, width, 3)")));
    };
    if f == 0 || h == 0 || w == 0 {
        return Err(PyValueError::new_err(format!("maps: shape {shape:?}: expected at least one texel of one frame")));
    }
    let ro = arr.try_readonly().map_err(|e| PyValueError::new_err(format!("maps: {e}")))?;
    let view = ro.as_array();
    let n = w * h;
    (0..f)
        .map(|k| {
            let mut planes = vec![0.0f32; 3 * n];
            for y in 0..h {
                for x in 0..w {
                    for c in 0..3 {
                        planes[c * n + y * w + x] = view[[k, y, x, c]] as f32;
                    }
                }
            }
            TextureImage::from_planes(w, h, 3, planes).py_err()
        })
        .collect()
}

/// One map `(H, W, 3)` uint8 (or a PNG/JPEG path) as an image; `what` names the argument.
fn map_of(a: &Bound<'_, PyAny>, what: &str) -> PyResult<(TextureImage, String)> {
    if let Ok(path) = a.extract::<PathBuf>() {
        let t = TextureImage::read(&path).py_err()?;
        return Ok((t, path.display().to_string()));
    }
    let arr = a
        .cast::<PyArrayDyn<u8>>()
        .map_err(|_| PyTypeError::new_err(format!("{what}: expected a PNG/JPEG path or an (H, W, 3) uint8 array")))?;
    let shape = arr.shape().to_vec();
    let [h, w, 3] = shape[..] else {
        return Err(PyValueError::new_err(format!("{what}: shape {shape:?}, expected (height, width, 3)")));
    };
    let ro = arr.try_readonly().map_err(|e| PyValueError::new_err(format!("{what}: {e}")))?;
    let view = ro.as_array();
    let n = w * h;
    let mut planes = vec![0.0f32; 3 * n];
    for y in 0..h {
        for x in 0..w {
            for c in 0..3 {
                planes[c * n + y * w + x] = view[[y, x, c]] as f32;
            }
        }
    }
    Ok((TextureImage::from_planes(w, h, 3, planes).py_err()?, what.to_string()))
}

/// Observed texels `(H, W)` bool as an image observed where it is not black (as the command
/// reads its `--observed` image), or a path to such an image.
fn observed_of(a: &Bound<'_, PyAny>) -> PyResult<(TextureImage, String)> {
    if a.extract::<PathBuf>().is_ok() {
        return map_of(a, "observed");
    }
    let np = a.py().import("numpy")?;
    let b = np.call_method1("asarray", (a, "bool"))?;
    let shape: Vec<usize> = b.getattr("shape")?.extract()?;
    let [h, w] = shape[..] else {
        return Err(PyValueError::new_err(format!("observed: shape {shape:?}, expected (height, width) booleans")));
    };
    let flat: Vec<bool> = b.call_method0("ravel")?.call_method0("tolist")?.extract()?;
    let n = w * h;
    let mut planes = vec![0.0f32; 3 * n];
    for (i, &o) in flat.iter().enumerate() {
        if o {
            for c in 0..3 {
                planes[c * n + i] = 255.0;
            }
        }
    }
    Ok((TextureImage::from_planes(w, h, 3, planes).py_err()?, "observed".to_string()))
}

/// An image as `(H, W, 3)` uint8 (rounded and clamped as its PNG is).
fn image_array<'py>(py: Python<'py>, t: &TextureImage) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
    crate::arrays::matrix(py, t.to_rgb8(), &[t.height(), t.width(), 3])
}

/// Writes `t` to `output` (PNG or JPEG by the extension) when asked, refusing to replace an
/// input.
fn write_image(t: &TextureImage, output: Option<&Path>, inputs: &[&Path]) -> PyResult<()> {
    if let Some(out) = output {
        surfcap_mesh::output_path::check_not_input(out, inputs).py_err()?;
        t.write(out).py_err()?;
    }
    Ok(())
}

fn warping(s: &str, what: &str) -> PyResult<Warping> {
    req::parse_warping(s)
        .ok_or_else(|| PyValueError::new_err(format!("{what}: {s}: expected poisson (thesis eq. 4.1-4.3) or direct")))
}

impl PyAppearanceModel {
    /// A model frame given as a name the model lists or an index.
    fn frame(&self, frame: &Bound<'_, PyAny>) -> PyResult<usize> {
        if let Ok(k) = frame.extract::<i64>() {
            let n = self.model.n_frames();
            if k < 0 || k as usize >= n {
                return Err(PyIndexError::new_err(format!("frame {k}: the model has frames 0 to {}", n - 1)));
            }
            return Ok(k as usize);
        }
        let name: String = frame
            .extract()
            .map_err(|_| PyTypeError::new_err("a frame is a name the model lists (str) or an index (int)"))?;
        req::frame_of(&self.model, &name).py_err()
    }
}

#[pymethods]
impl PyAppearanceModel {
    /// Builds the model of per-frame texture maps as `surfcap appearance build`. `maps`: a
    /// folder as the command reads it (PNG/JPEG maps in natural order; a folder of `surfcap
    /// appearance generate` gives its frames without the holed ones unless `keep_holed`), or
    /// an `(F, H, W, 3)` uint8 array. `mesh`: the UV-mapped mesh the maps follow, an OBJ path,
    /// any subject source or a `Subject` (default: the folder's `template.obj`); a subject of F
    /// frames names the frames `sequence:frame`, else they are named by `names`, the files'
    /// names or their indices. `components` eigen maps in all (two thirds textures), `lambda_`
    /// the Poisson warp's weight, `warping`/`search_warping` `"poisson"` or `"direct"`,
    /// `medoid_iterations`, `dilation`, `flow_scale`, `no_preprocess` as the command's options.
    /// With `output`, the model folder is written. Flows are cached as the command caches them
    /// (`cache_dir`, `cache=False`, `refresh=True`). The build's summary is `.report`.
    #[staticmethod]
    #[pyo3(signature = (maps, mesh=None, *, names=None, components=None, lambda_=0.02, warping="poisson", search_warping="direct", medoid_iterations=5, keep_holed=false, dilation=1, flow_scale=1, no_preprocess=false, output=None, force=false, cache_dir=None, cache=true, refresh=false))]
    #[allow(clippy::too_many_arguments)]
    fn build(
        py: Python<'_>,
        maps: &Bound<'_, PyAny>,
        mesh: Option<&Bound<'_, PyAny>>,
        names: Option<Vec<String>>,
        components: Option<usize>,
        lambda_: f64,
        warping: &str,
        search_warping: &str,
        medoid_iterations: usize,
        keep_holed: bool,
        dilation: usize,
        flow_scale: usize,
        no_preprocess: bool,
        output: Option<PathBuf>,
        force: bool,
        cache_dir: Option<PathBuf>,
        cache: bool,
        refresh: bool,
    ) -> PyResult<Self> {
        // The command's option checks.
        if let Some(k) = components
            && k < 2
        {
            return Err(PyValueError::new_err(format!("components: {k}: expected at least 2")));
        }
        if !(lambda_ > 0.0 && lambda_ <= 1000.0) {
            return Err(PyValueError::new_err(format!(
                "lambda_: {lambda_}: expected a number above 0 and at most 1000"
            )));
        }
        if medoid_iterations < 1 {
            return Err(PyValueError::new_err("medoid_iterations: expected at least 1"));
        }
        if dilation > 8 {
            return Err(PyValueError::new_err(format!("dilation: {dilation}: expected a whole number from 0 to 8")));
        }
        if flow_scale > 4 {
            return Err(PyValueError::new_err(format!(
                "flow_scale: {flow_scale}: expected a whole number from 0 to 4"
            )));
        }
        let warping = self::warping(warping, "warping")?;
        let selection_warping = self::warping(search_warping, "search_warping")?;
        let t0 = Instant::now();
        let progress = PyProgress::new();
        let folder: Option<PathBuf> = maps.extract::<PathBuf>().ok();
        // A folder without a mesh: its template.obj, named before any map is read.
        let folder_mesh = match (&folder, mesh) {
            (Some(dir), None) => Some(req::mesh_of(dir, None).py_err()?),
            _ => None,
        };
        // The maps and the names their files give.
        let (textures, file_names) = match &folder {
            Some(dir) => {
                let files = req::texture_files(dir, keep_holed, &progress).py_err()?;
                let textures = py.detach(|| read_textures(&files, &progress)).py_err()?;
                (textures, Some(files.iter().map(|f| frame_name(f)).collect::<Vec<_>>()))
            }
            None => (maps_of_array(maps)?, None),
        };
        let (w, h) = (textures[0].width(), textures[0].height());
        // The mesh: a Subject, a path (OBJ or subject source), or the folder's template.obj.
        let (mesh_name, topology, subject): (PathBuf, Topology, Option<Subject>) = match mesh {
            Some(m) if m.cast::<PySubject>().is_ok() => {
                let s = m.cast::<PySubject>()?.get().subject().clone();
                (PathBuf::from(&s.name), s.topology().clone(), Some(s))
            }
            Some(m) => {
                let p: PathBuf = m.extract().map_err(|_| PyTypeError::new_err("mesh: expected a path or a Subject"))?;
                open_mesh(py, &p, &progress)?
            }
            None => match &folder_mesh {
                Some(m) => open_mesh(py, m, &progress)?,
                None => {
                    return Err(PyTypeError::new_err(
                        "mesh: required with an array of maps (an OBJ path or a Subject)",
                    ));
                }
            },
        };
        // The model folder may not replace an input (refused before any work).
        if let Some(out) = &output {
            let mut inputs: Vec<&Path> = vec![&mesh_name];
            inputs.extend(folder.as_deref());
            surfcap_mesh::output_path::check_not_input(out, &inputs).py_err()?;
        }
        let (mask, subject_names) =
            req::atlas_mask(&mesh_name, &topology, subject.as_ref(), w, h, dilation, textures.len()).py_err()?;
        let names = match names {
            Some(n) if n.len() != textures.len() => {
                return Err(PyValueError::new_err(format!("names: {} names for {} maps", n.len(), textures.len())));
            }
            Some(n) => n,
            None => {
                subject_names.or(file_names).unwrap_or_else(|| (0..textures.len()).map(|k| k.to_string()).collect())
            }
        };
        let (n_textures, n_warps) =
            components.map_or((usize::MAX, usize::MAX), surfcap_appearance::appearance_model::split_components);
        let options = AppearanceOptions {
            lambda: lambda_,
            n_textures,
            n_warps,
            warping,
            max_medoid_iterations: medoid_iterations,
            selection_warping,
        };
        let choice = CacheChoice::new(cache_dir, cache, refresh);
        let (model, summary) = py
            .detach(|| -> surfcap_appearance::error::Result<_> {
                let flow = req::texture_flow(choice.dir.as_deref(), refresh, flow_scale, no_preprocess, &progress);
                let estimate = |r: &TextureImage, t: &TextureImage| flow.estimate(r, t, &mask);
                let (model, report) = build_appearance_model(&textures, &names, &mask, &options, &estimate, &progress)?;
                if let Some(out) = &output {
                    model.save(out, force)?;
                }
                let summary = req::build_summary(&model, &report, output.as_deref(), t0.elapsed().as_secs_f64());
                Ok((model, summary))
            })
            .py_err()?;
        drop(progress);
        Ok(PyAppearanceModel { model: Arc::new(model), report: Some(summary.to_string()), cache: choice })
    }

    /// Reads a model folder written by `surfcap appearance build` (or `save`). `complete`'s
    /// flows are cached in `cache_dir` (default: the command line's folder; `cache=False`:
    /// memory only; `refresh=True`: recompute).
    #[staticmethod]
    #[pyo3(signature = (path, *, cache_dir=None, cache=true, refresh=false))]
    fn load(py: Python<'_>, path: PathBuf, cache_dir: Option<PathBuf>, cache: bool, refresh: bool) -> PyResult<Self> {
        let model = py.detach(|| AppearanceModel::load(&path)).py_err()?;
        Ok(PyAppearanceModel {
            model: Arc::new(model),
            report: None,
            cache: CacheChoice::new(cache_dir, cache, refresh),
        })
    }

    /// Writes the model folder as `surfcap appearance build` does (the commands read it).
    /// Nothing surfcap did not write is replaced unless `force`.
    #[pyo3(signature = (path, *, force=false))]
    fn save(&self, py: Python<'_>, path: PathBuf, force: bool) -> PyResult<()> {
        let model = &self.model;
        py.detach(|| model.save(&path, force)).py_err()
    }

    /// The build's summary (`surfcap.reports.AppearanceBuildReport`, what `surfcap appearance
    /// build --json` prints), or None for a loaded model.
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.report.as_deref().map(|t| crate::reports::from_json(py, "AppearanceBuildReport", t)).transpose()
    }

    /// The frames' names, in the model's order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.model.names().to_vec()
    }

    /// The reference frame's name.
    #[getter]
    fn reference(&self) -> String {
        self.model.names()[self.model.reference()].clone()
    }

    #[getter]
    fn n_frames(&self) -> usize {
        self.model.n_frames()
    }

    #[getter]
    fn n_textures(&self) -> usize {
        self.model.n_textures()
    }

    #[getter]
    fn n_warps(&self) -> usize {
        self.model.n_warps()
    }

    /// `(height, width)` of the maps.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        (self.model.mask().height(), self.model.mask().width())
    }

    /// The active texels `(H, W)` bool (the atlas's, dilated).
    #[getter]
    fn mask<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArrayDyn<bool>>> {
        let m: &TexelMask = self.model.mask();
        let v: Vec<bool> = (0..m.width() * m.height()).map(|i| m.is_active(i)).collect();
        crate::arrays::matrix(py, v, &[m.height(), m.width()])
    }

    /// A training frame's map `(H, W, 3)` uint8 rebuilt from its coefficients, as `surfcap
    /// appearance reconstruct`: `frame` a name the model lists or an index, `components` eigen
    /// maps used (two thirds textures; default all). `output`: also write it (PNG or JPEG).
    #[pyo3(signature = (frame, *, components=None, output=None))]
    fn reconstruct<'py>(
        &self,
        py: Python<'py>,
        frame: &Bound<'py, PyAny>,
        components: Option<usize>,
        output: Option<PathBuf>,
    ) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        let k = self.frame(frame)?;
        let model = &self.model;
        let texture = py
            .detach(|| -> surfcap_appearance::error::Result<TextureImage> {
                let (tc, wc) = model.frame_coefficients(k)?;
                let (nt, nw) =
                    components.map_or((tc.len(), wc.len()), surfcap_appearance::appearance_model::split_components);
                model.instantiate(&tc[..nt.min(tc.len())], &wc[..nw.min(wc.len())])
            })
            .py_err()?;
        write_image(&texture, output.as_deref(), &[])?;
        image_array(py, &texture)
    }

    /// A map `(H, W, 3)` uint8 blended from `frames` (names or indices) in the eigen spaces, as
    /// `surfcap appearance interpolate` (4.6.1): `weights` one per frame (summing to 1), or
    /// None for equal weights. `output`: also write it (PNG or JPEG).
    #[pyo3(signature = (frames, weights=None, *, output=None))]
    fn interpolate<'py>(
        &self,
        py: Python<'py>,
        frames: Vec<Bound<'py, PyAny>>,
        weights: Option<Vec<f64>>,
        output: Option<PathBuf>,
    ) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        if let Some(w) = &weights
            && w.len() != frames.len()
        {
            return Err(PyValueError::new_err(format!("weights: {} weights for {} frames", w.len(), frames.len())));
        }
        let mut items = Vec::with_capacity(frames.len());
        for (i, f) in frames.iter().enumerate() {
            let k = self.frame(f)?;
            items.push((self.model.names()[k].clone(), weights.as_ref().map(|w| w[i])));
        }
        let weighted = req::frame_weights(&self.model, &items).py_err()?;
        let model = &self.model;
        let texture = py.detach(|| model.interpolate(&weighted)).py_err()?;
        write_image(&texture, output.as_deref(), &[])?;
        image_array(py, &texture)
    }

    /// An incomplete map completed by projection, as `surfcap appearance complete` (4.6.2):
    /// `texture` an `(H, W, 3)` uint8 array or a PNG/JPEG path of the model's size, `observed`
    /// its observed texels as an `(H, W)` bool array or an image (observed where not black;
    /// default: every texel that is not pure black). Returns the model's map `(H, W, 3)` uint8,
    /// with the observed texels kept as they are when `keep_observed`. `flow_scale`,
    /// `no_preprocess` as the command's options; `output`: also write it.
    #[pyo3(signature = (texture, observed=None, *, keep_observed=false, flow_scale=1, no_preprocess=false, output=None))]
    #[allow(clippy::too_many_arguments)]
    fn complete<'py>(
        &self,
        py: Python<'py>,
        texture: &Bound<'py, PyAny>,
        observed: Option<&Bound<'py, PyAny>>,
        keep_observed: bool,
        flow_scale: usize,
        no_preprocess: bool,
        output: Option<PathBuf>,
    ) -> PyResult<Bound<'py, PyArrayDyn<u8>>> {
        if flow_scale > 4 {
            return Err(PyValueError::new_err(format!(
                "flow_scale: {flow_scale}: expected a whole number from 0 to 4"
            )));
        }
        let (map, map_name) = map_of(texture, "texture")?;
        let observed_image = observed.map(observed_of).transpose()?;
        let (observed, _missing) =
            req::observed_texels(&self.model, &map, &map_name, observed_image.as_ref().map(|(o, n)| (o, n.as_str())))
                .py_err()?;
        let model = &self.model;
        let cache = &self.cache;
        let progress = PyProgress::new();
        let out = py
            .detach(|| -> surfcap_appearance::error::Result<TextureImage> {
                let flow = req::texture_flow(cache.dir.as_deref(), cache.refresh, flow_scale, no_preprocess, &progress);
                let estimate = |r: &TextureImage, t: &TextureImage, m: &TexelMask| flow.estimate(r, t, m);
                let mut out = model.complete(&map, &observed, &estimate)?;
                if keep_observed {
                    req::keep_observed(&mut out, &map, &observed);
                }
                Ok(out)
            })
            .py_err()?;
        drop(progress);
        write_image(&out, output.as_deref(), &[])?;
        image_array(py, &out)
    }

    fn __repr__(&self) -> String {
        let m = &self.model;
        format!(
            "AppearanceModel({} frames of {}x{}, reference {}, {} eigen textures, {} eigen warps)",
            m.n_frames(),
            m.mask().width(),
            m.mask().height(),
            m.names()[m.reference()],
            m.n_textures(),
            m.n_warps()
        )
    }
}

/// A mesh path: an OBJ's topology, or an opened subject (its notes logged).
fn open_mesh(py: Python<'_>, path: &Path, progress: &PyProgress) -> PyResult<(PathBuf, Topology, Option<Subject>)> {
    if req::is_obj(path) {
        let obj = surfcap_formats::obj::read_obj(path).py_err()?;
        let topology = obj.topology().map_err(|e| e.in_file(path)).py_err()?;
        return Ok((path.to_path_buf(), topology, None));
    }
    let imported = py.detach(|| surfcap_formats::import::open_subject(path, &Default::default(), progress)).py_err()?;
    for n in &imported.notes {
        surfcap_mesh::Progress::note(progress, n);
    }
    let s = imported.subject;
    Ok((path.to_path_buf(), s.topology().clone(), Some(s)))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyAppearanceModel>()
}
