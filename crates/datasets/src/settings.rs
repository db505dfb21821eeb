//! Camera settings files as ORB-SLAM2 and ORB-SLAM3 read them: the community's de facto camera
//! file. Written from a sequence's own camera (so another SLAM system can run on the same
//! files as noisefree, see `noisefree settings`), and read back (`noisefree run --camera`), so
//! a folder that is not named like a TUM sequence runs with the camera its settings file says.
//!
//! The files are OpenCV `FileStorage` YAML: a `%YAML:1.0` first line, `Key.name: value`
//! scalars, and `!!opencv-matrix` maps (`rows`, `cols`, `dt`, `data: [...]`). Every number is
//! written with the fewest digits that read back to the same `f64`, so a camera survives the
//! round trip bit for bit; reals always carry a decimal point (ORB-SLAM3 refuses an integer
//! where it expects a float).
//!
//! - ORB-SLAM2 (`Examples/RGB-D/TUM1.yaml`, `Examples/Stereo/EuRoC.yaml`): `Camera.fx` ...
//!   `Camera.k3`, `Camera.width`, `Camera.height`, `Camera.fps`, `Camera.bf`, `Camera.RGB`,
//!   `ThDepth`, `DepthMapFactor` (RGB-D), `ORBextractor.*`, `Viewer.*`; for a stereo rig the
//!   rectification its `stereo_euroc` applies: `LEFT.height`, `LEFT.width`, `LEFT.D`, `LEFT.K`,
//!   `LEFT.R`, `LEFT.P` and the same for `RIGHT`.
//! - ORB-SLAM3 (`File.version: "1.0"`): `Camera.type` (`PinHole`, or `Rectified` for a pair
//!   given rectified), `Camera1.fx` ... `Camera1.k3`, `Camera2.*` and `Stereo.T_c1_c2` for a
//!   raw stereo pair (ORB-SLAM3 rectifies it itself), `Camera.width`, `Camera.height`,
//!   `Camera.fps`, `Camera.RGB`, `Stereo.ThDepth`, `Stereo.b` (baseline in metres),
//!   `RGBD.DepthMapFactor`, `ORBextractor.*`, `Viewer.*`.

use crate::rectify::{RawCamera, StereoRectification};
use crate::DatasetError;
use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Translation3, UnitQuaternion, Vector2};
use slam_core::{Camera, Distortion, SensorKind};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// Which SLAM system's settings layout a file has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SettingsFormat {
    /// ORB-SLAM2's (also read by ORB-SLAM3 when `File.version` is absent).
    Orbslam2,
    /// ORB-SLAM3's `File.version: "1.0"` layout.
    Orbslam3,
}

impl SettingsFormat {
    /// Parses `orbslam2` / `orbslam3` (also `orb-slam2`, `orb-slam3`).
    pub fn parse(s: &str) -> Option<SettingsFormat> {
        match s.trim().to_ascii_lowercase().as_str() {
            "orbslam2" | "orb-slam2" | "orb_slam2" => Some(SettingsFormat::Orbslam2),
            "orbslam3" | "orb-slam3" | "orb_slam3" => Some(SettingsFormat::Orbslam3),
            _ => None,
        }
    }

    /// The command-line spelling.
    pub fn name(self) -> &'static str {
        match self {
            SettingsFormat::Orbslam2 => "orbslam2",
            SettingsFormat::Orbslam3 => "orbslam3",
        }
    }
}

/// ORB extractor settings of a settings file (`ORBextractor.*`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbSettings {
    /// `ORBextractor.nFeatures`.
    pub n_features: usize,
    /// `ORBextractor.scaleFactor`.
    pub scale_factor: f64,
    /// `ORBextractor.nLevels`.
    pub n_levels: usize,
    /// `ORBextractor.iniThFAST`.
    pub ini_th_fast: u8,
    /// `ORBextractor.minThFAST`.
    pub min_th_fast: u8,
}

impl OrbSettings {
    /// ORB-SLAM2's extractor for a sensor: 1000 features for TUM RGB-D, 1200 for EuRoC stereo;
    /// scale 1.2, 8 levels, FAST 20 / 7.
    pub fn orbslam2(sensor: SensorKind) -> OrbSettings {
        OrbSettings {
            n_features: match sensor {
                SensorKind::Rgbd => 1000,
                SensorKind::Stereo => 1200,
            },
            scale_factor: 1.2,
            n_levels: 8,
            ini_th_fast: 20,
            min_th_fast: 7,
        }
    }
}

/// A raw stereo pair and the rectification applied to it: what ORB-SLAM2's `LEFT.*` /
/// `RIGHT.*` entries describe. The rectified intrinsics are the settings' camera.
#[derive(Clone, Debug, PartialEq)]
pub struct StereoRig {
    /// The raw left camera (intrinsics, distortion; `t_bs` identity unless known).
    pub left: RawCamera,
    /// The raw right camera.
    pub right: RawCamera,
    /// Rectifying rotation of the left camera (`X_rect = r_left * X_raw`).
    pub r_left: Rotation3<f64>,
    /// Rectifying rotation of the right camera.
    pub r_right: Rotation3<f64>,
}

/// Everything a settings file says about a sequence's camera.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraSettings {
    /// The camera slam-core sees (rectified for stereo; width / height 0 when the file did not
    /// say, as ORB-SLAM2's TUM files do not: the reader takes them from the images).
    pub camera: Camera,
    /// RGB-D: depth PNG value per metre (`DepthMapFactor`).
    pub depth_factor: Option<f64>,
    /// Stereo: the raw pair and its rectification, when the images are raw.
    pub rig: Option<StereoRig>,
    /// Stereo (ORB-SLAM3 `PinHole`): the raw pair without a rectification, which the reader
    /// computes (`Stereo.T_c1_c2` in the right camera's `t_bs`).
    pub raw_pair: Option<(RawCamera, RawCamera)>,
    /// The ORB extractor.
    pub orb: OrbSettings,
    /// `Camera.RGB`: 1 when colour images are RGB, 0 for BGR.
    pub rgb: bool,
}

impl CameraSettings {
    /// Settings of a camera as noisefree sees it: `depth_factor` for RGB-D, and for stereo the
    /// rectification of the raw pair (`None`: the images are rectified already, given as an
    /// identity rectification).
    pub fn of_camera(
        camera: &Camera,
        depth_factor: Option<f64>,
        rectification: Option<&StereoRectification>,
    ) -> CameraSettings {
        let rig = match (camera.sensor, rectification) {
            (SensorKind::Rgbd, _) => None,
            (SensorKind::Stereo, Some(r)) => Some(StereoRig {
                left: r.left_raw().clone(),
                right: r.right_raw().clone(),
                r_left: r.r_left,
                r_right: r.r_right,
            }),
            (SensorKind::Stereo, None) => {
                let raw = RawCamera {
                    width: camera.width,
                    height: camera.height,
                    fx: camera.fx,
                    fy: camera.fy,
                    cx: camera.cx,
                    cy: camera.cy,
                    distortion: no_distortion(),
                    t_bs: Isometry3::identity(),
                    rate_hz: camera.fps,
                };
                Some(StereoRig {
                    left: raw.clone(),
                    right: raw,
                    r_left: Rotation3::identity(),
                    r_right: Rotation3::identity(),
                })
            }
        };
        CameraSettings {
            camera: camera.clone(),
            depth_factor: match camera.sensor {
                SensorKind::Rgbd => Some(depth_factor.unwrap_or(5000.0)),
                SensorKind::Stereo => None,
            },
            rig,
            raw_pair: None,
            orb: OrbSettings::orbslam2(camera.sensor),
            rgb: true,
        }
    }

    /// Settings of a sequence as noisefree reads it: its camera, depth factor and (stereo) the
    /// rectification of its raw images.
    pub fn of_sequence(seq: &crate::Sequence) -> CameraSettings {
        CameraSettings::of_camera(&seq.camera, seq.depth_factor, seq.rectification.as_deref())
    }

    /// The rectification this file gives for a stereo pair whose raw left camera sits at
    /// `t_bs_left` in the body frame (from the folder's `sensor.yaml`; identity when unknown):
    /// the file's own `LEFT.*`/`RIGHT.*` (ORB-SLAM2), or one computed from ORB-SLAM3's raw
    /// pair. `None` when the file has neither (the images are taken as rectified).
    pub fn rectification(
        &self,
        path: &Path,
        t_bs_left: Isometry3<f64>,
    ) -> Result<Option<StereoRectification>, DatasetError> {
        if let Some(rig) = &self.rig {
            let mut left = rig.left.clone();
            left.t_bs = t_bs_left;
            let c = &self.camera;
            if c.fx != c.fy {
                return Err(DatasetError::invalid(
                    path,
                    format!(
                        "a rectified stereo camera needs fx = fy (got {} and {})",
                        c.fx, c.fy
                    ),
                ));
            }
            let baseline = c.bf / c.fx;
            return StereoRectification::from_parts(
                &left,
                &rig.right,
                rig.r_left,
                rig.r_right,
                c.fx,
                Vector2::new(c.cx, c.cy),
                baseline,
            )
            .map(Some)
            .map_err(|e| DatasetError::invalid(path, e.to_string()));
        }
        if let Some((l, r)) = &self.raw_pair {
            let mut left = l.clone();
            let mut right = r.clone();
            // Stereo.T_c1_c2 is the right camera in the left's frame; keep that relation.
            right.t_bs = t_bs_left * right.t_bs;
            left.t_bs = t_bs_left;
            return StereoRectification::new(&left, &right)
                .map(Some)
                .map_err(|e| DatasetError::invalid(path, e.to_string()));
        }
        Ok(None)
    }
}

fn no_distortion() -> Distortion {
    Distortion {
        k1: 0.0,
        k2: 0.0,
        p1: 0.0,
        p2: 0.0,
        k3: 0.0,
    }
}

/// A real number as OpenCV's YAML reads it back to the same `f64`: the shortest round-trip
/// digits, with a decimal point even for whole numbers.
pub fn real(x: f64) -> String {
    let s = format!("{x}");
    if !x.is_finite() || s.contains('.') || s.contains('e') {
        s
    } else {
        s + ".0"
    }
}

fn matrix(out: &mut String, key: &str, rows: usize, cols: usize, data: &[f64]) {
    matrix_typed(out, key, rows, cols, data, 'd');
}

/// An `!!opencv-matrix` of element type `dt` (`d` double, `f` float: ORB-SLAM3 reads
/// `Stereo.T_c1_c2` as floats and misreads doubles).
fn matrix_typed(out: &mut String, key: &str, rows: usize, cols: usize, data: &[f64], dt: char) {
    let _ = writeln!(out, "{key}: !!opencv-matrix");
    let _ = writeln!(out, "   rows: {rows}");
    let _ = writeln!(out, "   cols: {cols}");
    let _ = writeln!(out, "   dt: {dt}");
    let cells: Vec<String> = data.iter().map(|&v| real(v)).collect();
    let _ = writeln!(out, "   data: [{}]", cells.join(", "));
}

fn rotation_data(r: &Rotation3<f64>) -> Vec<f64> {
    let m = r.matrix();
    (0..3)
        .flat_map(|i| (0..3).map(move |j| (i, j)))
        .map(|(i, j)| m[(i, j)])
        .collect()
}

fn viewer(out: &mut String) {
    // ORB-SLAM2's and ORB-SLAM3's viewer reads these (its example files' values).
    out.push_str(
        "\n# Viewer (read by the systems' viewers; the values of their example files)\n\
         Viewer.KeyFrameSize: 0.05\nViewer.KeyFrameLineWidth: 1.0\nViewer.GraphLineWidth: 0.9\n\
         Viewer.PointSize: 2.0\nViewer.CameraSize: 0.08\nViewer.CameraLineWidth: 3.0\n\
         Viewer.ViewpointX: 0.0\nViewer.ViewpointY: -0.7\nViewer.ViewpointZ: -1.8\n\
         Viewer.ViewpointF: 500.0\n",
    );
}

fn orb(out: &mut String, o: &OrbSettings) {
    let _ = writeln!(out, "\n# ORB extractor");
    let _ = writeln!(out, "ORBextractor.nFeatures: {}", o.n_features);
    let _ = writeln!(out, "ORBextractor.scaleFactor: {}", real(o.scale_factor));
    let _ = writeln!(out, "ORBextractor.nLevels: {}", o.n_levels);
    let _ = writeln!(out, "ORBextractor.iniThFAST: {}", o.ini_th_fast);
    let _ = writeln!(out, "ORBextractor.minThFAST: {}", o.min_th_fast);
}

fn distortion_of(c: &Camera) -> Distortion {
    c.distortion.unwrap_or_else(no_distortion)
}

/// The settings file of `s` in `format`, headed by a comment naming `title` (e.g. the
/// sequence).
pub fn write_settings(s: &CameraSettings, format: SettingsFormat, title: &str) -> String {
    match format {
        SettingsFormat::Orbslam2 => write_orbslam2(s, title),
        SettingsFormat::Orbslam3 => write_orbslam3(s, title),
    }
}

fn write_orbslam2(s: &CameraSettings, title: &str) -> String {
    let c = &s.camera;
    let d = distortion_of(c);
    let mut out = String::from("%YAML:1.0\n");
    let _ = writeln!(
        out,
        "# ORB-SLAM2 settings of {title}, written by noisefree from the sequence's own camera\n"
    );
    for (k, v) in [
        ("fx", c.fx),
        ("fy", c.fy),
        ("cx", c.cx),
        ("cy", c.cy),
        ("k1", d.k1),
        ("k2", d.k2),
        ("p1", d.p1),
        ("p2", d.p2),
        ("k3", d.k3),
    ] {
        let _ = writeln!(out, "Camera.{k}: {}", real(v));
    }
    let _ = writeln!(out, "Camera.width: {}", c.width);
    let _ = writeln!(out, "Camera.height: {}", c.height);
    let _ = writeln!(out, "Camera.fps: {}", real(c.fps));
    let _ = writeln!(
        out,
        "# stereo baseline (or the RGB-D virtual one) times fx\nCamera.bf: {}",
        real(c.bf)
    );
    let _ = writeln!(
        out,
        "# colour order of the images (0: BGR, 1: RGB; ignored for grey images)\nCamera.RGB: {}",
        u8::from(s.rgb)
    );
    let _ = writeln!(
        out,
        "# close / far threshold: ThDepth * bf / fx metres\nThDepth: {}",
        real(c.th_depth)
    );
    if let Some(f) = s.depth_factor {
        let _ = writeln!(
            out,
            "# depth PNG value per metre\nDepthMapFactor: {}",
            real(f)
        );
    }
    if let Some(rig) = &s.rig {
        out.push_str("\n# the rectification of the raw stereo pair (stereo_euroc applies it)\n");
        for (side, cam, r, tx) in [
            ("LEFT", &rig.left, &rig.r_left, 0.0),
            ("RIGHT", &rig.right, &rig.r_right, -c.bf),
        ] {
            let _ = writeln!(out, "{side}.height: {}", cam.height);
            let _ = writeln!(out, "{side}.width: {}", cam.width);
            let dd = &cam.distortion;
            matrix(
                &mut out,
                &format!("{side}.D"),
                1,
                5,
                &[dd.k1, dd.k2, dd.p1, dd.p2, dd.k3],
            );
            matrix(
                &mut out,
                &format!("{side}.K"),
                3,
                3,
                &[cam.fx, 0.0, cam.cx, 0.0, cam.fy, cam.cy, 0.0, 0.0, 1.0],
            );
            matrix(&mut out, &format!("{side}.R"), 3, 3, &rotation_data(r));
            matrix(
                &mut out,
                &format!("{side}.P"),
                3,
                4,
                &[
                    c.fx, 0.0, c.cx, tx, 0.0, c.fy, c.cy, 0.0, 0.0, 0.0, 1.0, 0.0,
                ],
            );
        }
    }
    orb(&mut out, &s.orb);
    viewer(&mut out);
    out
}

fn write_camera1(out: &mut String, key: &str, fx: f64, fy: f64, cx: f64, cy: f64) {
    for (k, v) in [("fx", fx), ("fy", fy), ("cx", cx), ("cy", cy)] {
        let _ = writeln!(out, "{key}.{k}: {}", real(v));
    }
}

fn write_distortion(out: &mut String, key: &str, d: &Distortion) {
    for (k, v) in [("k1", d.k1), ("k2", d.k2), ("p1", d.p1), ("p2", d.p2)] {
        let _ = writeln!(out, "{key}.{k}: {}", real(v));
    }
    if d.k3 != 0.0 {
        let _ = writeln!(out, "{key}.k3: {}", real(d.k3));
    }
}

fn write_orbslam3(s: &CameraSettings, title: &str) -> String {
    let c = &s.camera;
    let mut out = String::from("%YAML:1.0\n");
    let _ = writeln!(
        out,
        "# ORB-SLAM3 settings of {title}, written by noisefree from the sequence's own camera\n"
    );
    out.push_str("File.version: \"1.0\"\n\n");
    // A raw stereo pair (distortion or a rotation to undo) is left to ORB-SLAM3's own
    // rectification; a pair already rectified is `Rectified`.
    let raw_rig = s.rig.as_ref().filter(|rig| {
        rig.r_left != Rotation3::identity()
            || rig.r_right != Rotation3::identity()
            || rig.left.distortion != no_distortion()
            || rig.right.distortion != no_distortion()
    });
    match (c.sensor, raw_rig) {
        (SensorKind::Stereo, Some(rig)) => {
            out.push_str("Camera.type: \"PinHole\"\n\n");
            for (key, cam) in [("Camera1", &rig.left), ("Camera2", &rig.right)] {
                write_camera1(&mut out, key, cam.fx, cam.fy, cam.cx, cam.cy);
                write_distortion(&mut out, key, &cam.distortion);
                out.push('\n');
            }
            // T_c1_c2: the right raw camera in the left raw camera's frame.
            let t = rig.left.t_bs.inverse() * rig.right.t_bs;
            let m: Matrix4<f64> = t.to_homogeneous();
            let data: Vec<f64> = (0..4)
                .flat_map(|i| (0..4).map(move |j| (i, j)))
                .map(|(i, j)| m[(i, j)])
                .collect();
            matrix_typed(&mut out, "Stereo.T_c1_c2", 4, 4, &data, 'f');
        }
        (SensorKind::Stereo, None) => {
            out.push_str("Camera.type: \"Rectified\"\n\n");
            write_camera1(&mut out, "Camera1", c.fx, c.fy, c.cx, c.cy);
            let _ = writeln!(out, "Stereo.b: {}", real(c.bf / c.fx));
        }
        (SensorKind::Rgbd, _) => {
            if c.distortion.is_some_and(|d| d != no_distortion()) {
                out.push_str(
                    "# Note: ORB-SLAM3 1.0 reads but does not apply an RGB-D camera's distortion\n\
                     # (its Settings hands Tracking zero coefficients outside monocular).\n",
                );
            }
            out.push_str("Camera.type: \"PinHole\"\n\n");
            write_camera1(&mut out, "Camera1", c.fx, c.fy, c.cx, c.cy);
            write_distortion(&mut out, "Camera1", &distortion_of(c));
            let _ = writeln!(
                out,
                "# the virtual stereo baseline, metres (bf / fx)\nStereo.b: {}",
                real(c.bf / c.fx)
            );
        }
    }
    let _ = writeln!(out, "\nCamera.width: {}", c.width);
    let _ = writeln!(out, "Camera.height: {}", c.height);
    let _ = writeln!(out, "Camera.fps: {}", c.fps.round() as i64);
    let _ = writeln!(out, "Camera.RGB: {}", u8::from(s.rgb));
    let _ = writeln!(out, "Stereo.ThDepth: {}", real(c.th_depth));
    if let Some(f) = s.depth_factor {
        let _ = writeln!(out, "RGBD.DepthMapFactor: {}", real(f));
    }
    orb(&mut out, &s.orb);
    viewer(&mut out);
    out
}

/// One entry of an OpenCV YAML file.
#[derive(Clone, Debug, PartialEq)]
enum Node {
    /// A scalar, unquoted.
    Scalar(String),
    /// An `!!opencv-matrix`: rows, cols, row-major data.
    Matrix(usize, usize, Vec<f64>),
}

/// The top-level entries of an OpenCV YAML file with their 1-based lines.
struct Entries<'a> {
    path: &'a Path,
    map: BTreeMap<String, (Node, usize)>,
}

fn strip_comment(l: &str) -> &str {
    let mut quoted = false;
    for (i, ch) in l.char_indices() {
        match ch {
            '"' => quoted = !quoted,
            '#' if !quoted => return &l[..i],
            _ => {}
        }
    }
    l
}

fn parse_entries<'a>(path: &'a Path, text: &str) -> Result<Entries<'a>, DatasetError> {
    let lines: Vec<&str> = text.lines().collect();
    let mut map = BTreeMap::new();
    let mut i = 0;
    while i < lines.len() {
        let line_no = i + 1;
        let raw = strip_comment(lines[i]);
        i += 1;
        let t = raw.trim();
        if t.is_empty() || t.starts_with('%') || t == "---" || t == "..." {
            continue;
        }
        if raw.starts_with(char::is_whitespace) {
            return Err(DatasetError::parse(
                path,
                line_no,
                format!("unexpected indented line `{t}`"),
            ));
        }
        let Some((key, value)) = t.split_once(':') else {
            return Err(DatasetError::parse(
                path,
                line_no,
                format!("expected `Key: value`, got `{t}`"),
            ));
        };
        let (key, value) = (key.trim().to_string(), value.trim());
        let node = if value.starts_with("!!opencv-matrix") || value.is_empty() {
            // The matrix's indented block: rows, cols, dt, data (which may span lines).
            let mut fields: BTreeMap<String, String> = BTreeMap::new();
            let mut data = String::new();
            let mut in_data = false;
            while i < lines.len() {
                let l = strip_comment(lines[i]);
                if !(l.starts_with(char::is_whitespace) || l.trim().is_empty()) {
                    break;
                }
                i += 1;
                let l = l.trim();
                if l.is_empty() {
                    continue;
                }
                if in_data {
                    data.push_str(l);
                    data.push(' ');
                    in_data = !l.contains(']');
                    continue;
                }
                let Some((k, v)) = l.split_once(':') else {
                    return Err(DatasetError::parse(
                        path,
                        i,
                        format!("expected `field: value` in matrix `{key}`, got `{l}`"),
                    ));
                };
                if k.trim() == "data" {
                    data.push_str(v);
                    data.push(' ');
                    in_data = !v.contains(']');
                } else {
                    fields.insert(k.trim().to_string(), v.trim().to_string());
                }
            }
            let dim = |name: &str| -> Result<usize, DatasetError> {
                fields
                    .get(name)
                    .and_then(|v| v.parse().ok())
                    .ok_or_else(|| {
                        DatasetError::parse(
                            path,
                            line_no,
                            format!("matrix `{key}` has no valid `{name}`"),
                        )
                    })
            };
            let (rows, cols) = (dim("rows")?, dim("cols")?);
            let inner = data.trim().trim_start_matches('[').trim_end_matches(']');
            let values: Vec<f64> = inner
                .split(',')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(|s| match s.parse::<f64>() {
                    Ok(v) if v.is_finite() => Ok(v),
                    _ => Err(DatasetError::parse(
                        path,
                        line_no,
                        format!("matrix `{key}`: `{s}` is not a finite number"),
                    )),
                })
                .collect::<Result<_, _>>()?;
            // Checked: `rows` and `cols` are the file's, and their product may overflow.
            if rows.checked_mul(cols) != Some(values.len()) {
                return Err(DatasetError::parse(
                    path,
                    line_no,
                    format!(
                        "matrix `{key}` is {rows}x{cols} but has {} values",
                        values.len()
                    ),
                ));
            }
            Node::Matrix(rows, cols, values)
        } else {
            Node::Scalar(value.trim_matches('"').trim_matches('\'').to_string())
        };
        map.insert(key, (node, line_no));
    }
    Ok(Entries { path, map })
}

impl Entries<'_> {
    fn has(&self, key: &str) -> bool {
        self.map.contains_key(key)
    }

    fn scalar(&self, key: &str) -> Result<Option<(&str, usize)>, DatasetError> {
        match self.map.get(key) {
            None => Ok(None),
            Some((Node::Scalar(s), line)) => Ok(Some((s.as_str(), *line))),
            Some((Node::Matrix(..), line)) => Err(DatasetError::parse(
                self.path,
                *line,
                format!("`{key}` is a matrix, expected a number"),
            )),
        }
    }

    fn real_opt(&self, key: &str) -> Result<Option<f64>, DatasetError> {
        match self.scalar(key)? {
            None => Ok(None),
            Some((s, line)) => match s.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(Some(v)),
                _ => Err(DatasetError::parse(
                    self.path,
                    line,
                    format!("`{key}: {s}` is not a finite number"),
                )),
            },
        }
    }

    fn real(&self, key: &str) -> Result<f64, DatasetError> {
        self.real_opt(key)?.ok_or_else(|| {
            DatasetError::invalid(self.path, format!("no `{key}` (a required setting)"))
        })
    }

    fn uint_opt(&self, key: &str) -> Result<Option<u64>, DatasetError> {
        match self.real_opt(key)? {
            None => Ok(None),
            Some(v) if v >= 0.0 && v.fract() == 0.0 && v < 1e12 => Ok(Some(v as u64)),
            Some(v) => Err(DatasetError::parse(
                self.path,
                self.map.get(key).map_or(0, |e| e.1),
                format!("`{key}: {v}` is not a whole number"),
            )),
        }
    }

    fn matrix(&self, key: &str, rows: usize, cols: usize) -> Result<Vec<f64>, DatasetError> {
        match self.map.get(key) {
            None => Err(DatasetError::invalid(
                self.path,
                format!("no `{key}` matrix (a required setting)"),
            )),
            Some((Node::Matrix(r, c, d), line)) => {
                // OpenCV reads a 1x5 distortion as 5x1 too.
                if (*r, *c) == (rows, cols)
                    || (r.checked_mul(*c) == Some(rows * cols) && (rows == 1 || cols == 1))
                {
                    Ok(d.clone())
                } else {
                    Err(DatasetError::parse(
                        self.path,
                        *line,
                        format!("`{key}` is {r}x{c}, expected {rows}x{cols}"),
                    ))
                }
            }
            Some((Node::Scalar(_), line)) => Err(DatasetError::parse(
                self.path,
                *line,
                format!("`{key}` is a number, expected an !!opencv-matrix"),
            )),
        }
    }

    fn distortion(&self, prefix: &str) -> Result<Distortion, DatasetError> {
        Ok(Distortion {
            k1: self.real_opt(&format!("{prefix}.k1"))?.unwrap_or(0.0),
            k2: self.real_opt(&format!("{prefix}.k2"))?.unwrap_or(0.0),
            p1: self.real_opt(&format!("{prefix}.p1"))?.unwrap_or(0.0),
            p2: self.real_opt(&format!("{prefix}.p2"))?.unwrap_or(0.0),
            k3: self.real_opt(&format!("{prefix}.k3"))?.unwrap_or(0.0),
        })
    }

    fn orb(&self, sensor: SensorKind) -> Result<OrbSettings, DatasetError> {
        let d = OrbSettings::orbslam2(sensor);
        let small = |key: &str, default: u8| -> Result<u8, DatasetError> {
            Ok(match self.uint_opt(key)? {
                None => default,
                Some(v) => u8::try_from(v).map_err(|_| {
                    DatasetError::invalid(self.path, format!("`{key}: {v}` is above 255"))
                })?,
            })
        };
        Ok(OrbSettings {
            n_features: self
                .uint_opt("ORBextractor.nFeatures")?
                .map_or(d.n_features, |v| v as usize),
            scale_factor: self
                .real_opt("ORBextractor.scaleFactor")?
                .unwrap_or(d.scale_factor),
            n_levels: self
                .uint_opt("ORBextractor.nLevels")?
                .map_or(d.n_levels, |v| v as usize),
            ini_th_fast: small("ORBextractor.iniThFAST", d.ini_th_fast)?,
            min_th_fast: small("ORBextractor.minThFAST", d.min_th_fast)?,
        })
    }

    /// An image size (0 where the file gives none). Checked here, before anything is built
    /// from it: an ORB-SLAM3 raw pair is rectified while the file is read, and a fuzzed
    /// `Camera.width: 742949672955` asked for an 824 GB rectification map.
    fn size(&self, w: &str, h: &str) -> Result<(u32, u32), DatasetError> {
        let get = |k: &str| -> Result<u32, DatasetError> {
            match self.uint_opt(k)? {
                None => Ok(0),
                Some(v) if v <= u64::from(MAX_IMAGE_SIDE) => Ok(v as u32),
                Some(v) => Err(DatasetError::parse(
                    self.path,
                    self.map.get(k).map_or(0, |e| e.1),
                    format!("{k} = {v}: must be <= {MAX_IMAGE_SIDE}"),
                )),
            }
        };
        Ok((get(w)?, get(h)?))
    }
}

fn raw_camera(width: u32, height: u32, k: &[f64], distortion: Distortion, fps: f64) -> RawCamera {
    RawCamera {
        width,
        height,
        fx: k[0],
        fy: k[4],
        cx: k[2],
        cy: k[5],
        distortion,
        t_bs: Isometry3::identity(),
        rate_hz: fps,
    }
}

fn rotation(m: &[f64]) -> Rotation3<f64> {
    Rotation3::from_matrix_unchecked(Matrix3::from_row_slice(m))
}

/// Reads an ORB-SLAM2 or ORB-SLAM3 settings file for a sequence of `sensor` (the folder's
/// layout decides: TUM RGB-D or EuRoC stereo). Missing required entries, malformed numbers
/// and unsupported camera models are errors naming the file (and line).
pub fn read_settings(path: &Path, sensor: SensorKind) -> Result<CameraSettings, DatasetError> {
    let text = std::fs::read_to_string(path).map_err(|e| DatasetError::io(path, e))?;
    if !text.trim_start().starts_with("%YAML") && !text.contains("Camera") {
        return Err(DatasetError::invalid(
            path,
            "not an ORB-SLAM2 / ORB-SLAM3 settings file (no %YAML header, no Camera entries)",
        ));
    }
    let e = parse_entries(path, &text)?;
    let (s, o3) = if e.has("File.version") {
        (read_orbslam3(&e, sensor)?, true)
    } else {
        (read_orbslam2(&e, sensor)?, false)
    };
    check_ranges(&e, &s, o3)?;
    Ok(s)
}

/// Largest image side a settings file or `sensor.yaml` may give, pixels: an 8K sensor. The
/// rectification of a stereo pair allocates maps of the image's size (8 bytes a pixel a
/// camera) as soon as the file is read, so a mistyped or corrupt size must not reach it.
pub const MAX_IMAGE_SIDE: u32 = 8192;

/// Checks the values a settings file gave against their valid ranges: a value that parses but
/// makes no sense (`ORBextractor.scaleFactor: 0.5`, a negative focal length) is refused with
/// its key, its line, its value and the range.
fn check_ranges(e: &Entries, s: &CameraSettings, o3: bool) -> Result<(), DatasetError> {
    let c = &s.camera;
    let cam = if o3 { "Camera1" } else { "Camera" };
    let th = if o3 { "Stereo.ThDepth" } else { "ThDepth" };
    let factor = if o3 {
        "RGBD.DepthMapFactor"
    } else {
        "DepthMapFactor"
    };
    let side = MAX_IMAGE_SIDE as f64;
    let o = &s.orb;
    let mut checks: Vec<(String, f64, bool, String)> = vec![
        (format!("{cam}.fx"), c.fx, c.fx > 0.0, "must be > 0".into()),
        (format!("{cam}.fy"), c.fy, c.fy > 0.0, "must be > 0".into()),
        (
            "Camera.width".into(),
            c.width as f64,
            c.width <= MAX_IMAGE_SIDE,
            format!("must be <= {side}"),
        ),
        (
            "Camera.height".into(),
            c.height as f64,
            c.height <= MAX_IMAGE_SIDE,
            format!("must be <= {side}"),
        ),
        (
            "Camera.fps".into(),
            c.fps,
            c.fps > 0.0 && c.fps <= 10_000.0,
            "must be > 0 and <= 10000".into(),
        ),
        (
            th.into(),
            c.th_depth,
            c.th_depth > 0.0,
            "must be > 0".into(),
        ),
        (
            "ORBextractor.nFeatures".into(),
            o.n_features as f64,
            (1..=200_000).contains(&o.n_features),
            "must be in 1..=200000".into(),
        ),
        (
            "ORBextractor.scaleFactor".into(),
            o.scale_factor,
            o.scale_factor > 1.0,
            "must be > 1".into(),
        ),
        (
            "ORBextractor.scaleFactor".into(),
            o.scale_factor,
            o.scale_factor <= 4.0,
            "must be <= 4".into(),
        ),
        (
            "ORBextractor.nLevels".into(),
            o.n_levels as f64,
            (1..=32).contains(&o.n_levels),
            "must be in 1..=32".into(),
        ),
        (
            "ORBextractor.iniThFAST".into(),
            o.ini_th_fast as f64,
            o.ini_th_fast >= 1,
            "must be in 1..=255".into(),
        ),
        (
            "ORBextractor.minThFAST".into(),
            o.min_th_fast as f64,
            o.min_th_fast >= 1 && o.min_th_fast <= o.ini_th_fast,
            format!("must be in 1..={} (iniThFAST)", o.ini_th_fast.max(1)),
        ),
    ];
    let bf = if o3 { "Stereo.b" } else { "Camera.bf" };
    match c.sensor {
        SensorKind::Stereo => checks.push((bf.into(), c.bf, c.bf > 0.0, "must be > 0".into())),
        SensorKind::Rgbd => checks.push((bf.into(), c.bf, c.bf >= 0.0, "must be >= 0".into())),
    }
    if let Some(f) = s.depth_factor {
        checks.push((factor.into(), f, f > 0.0, "must be > 0".into()));
    }
    for cam in s
        .rig
        .iter()
        .flat_map(|r| [&r.left, &r.right])
        .chain(s.raw_pair.iter().flat_map(|(l, r)| [l, r]))
    {
        for (k, v) in [("width", cam.width), ("height", cam.height)] {
            checks.push((
                format!("LEFT.{k} / RIGHT.{k}"),
                v as f64,
                v <= MAX_IMAGE_SIDE,
                format!("must be <= {side}"),
            ));
        }
        for (k, v) in [("fx", cam.fx), ("fy", cam.fy)] {
            checks.push((
                format!("the raw cameras' {k}"),
                v,
                v > 0.0,
                "must be > 0".into(),
            ));
        }
    }
    for (key, value, ok, rule) in checks {
        if !(ok && value.is_finite()) {
            let line = e.map.get(&key).map_or(0, |entry| entry.1);
            return Err(DatasetError::parse(
                e.path,
                line,
                format!("{key} = {value}: {rule}"),
            ));
        }
    }
    Ok(())
}

fn read_orbslam2(e: &Entries, sensor: SensorKind) -> Result<CameraSettings, DatasetError> {
    let fps = e.real_opt("Camera.fps")?.unwrap_or(30.0);
    let (width, height) = e.size("Camera.width", "Camera.height")?;
    let d = e.distortion("Camera")?;
    let camera = Camera {
        fx: e.real("Camera.fx")?,
        fy: e.real("Camera.fy")?,
        cx: e.real("Camera.cx")?,
        cy: e.real("Camera.cy")?,
        width,
        height,
        distortion: (d != no_distortion()).then_some(d),
        bf: e.real("Camera.bf")?,
        th_depth: e.real("ThDepth")?,
        fps,
        sensor,
    };
    let rig = if sensor == SensorKind::Stereo && e.has("LEFT.K") {
        let side = |s: &str| -> Result<(RawCamera, Rotation3<f64>), DatasetError> {
            let k = e.matrix(&format!("{s}.K"), 3, 3)?;
            let dd = e.matrix(&format!("{s}.D"), 1, 5).or_else(|_| {
                e.matrix(&format!("{s}.D"), 1, 4).map(|mut v| {
                    v.push(0.0);
                    v
                })
            })?;
            let r = e.matrix(&format!("{s}.R"), 3, 3)?;
            let (w, h) = e.size(&format!("{s}.width"), &format!("{s}.height"))?;
            let dist = Distortion {
                k1: dd[0],
                k2: dd[1],
                p1: dd[2],
                p2: dd[3],
                k3: dd[4],
            };
            Ok((
                raw_camera(
                    if w > 0 { w } else { width },
                    if h > 0 { h } else { height },
                    &k,
                    dist,
                    fps,
                ),
                rotation(&r),
            ))
        };
        let (left, r_left) = side("LEFT")?;
        let (right, r_right) = side("RIGHT")?;
        // The projection of the rectified left camera must be the settings' camera.
        let p = e.matrix("LEFT.P", 3, 4)?;
        if (p[0], p[2], p[6]) != (camera.fx, camera.cx, camera.cy) {
            return Err(DatasetError::invalid(
                e.path,
                format!(
                    "LEFT.P (fx {}, cx {}, cy {}) disagrees with Camera.fx/cx/cy ({}, {}, {})",
                    p[0], p[2], p[6], camera.fx, camera.cx, camera.cy
                ),
            ));
        }
        Some(StereoRig {
            left,
            right,
            r_left,
            r_right,
        })
    } else {
        None
    };
    let camera = Camera {
        width: if camera.width == 0 {
            rig.as_ref().map_or(0, |r| r.left.width)
        } else {
            camera.width
        },
        height: if camera.height == 0 {
            rig.as_ref().map_or(0, |r| r.left.height)
        } else {
            camera.height
        },
        ..camera
    };
    Ok(CameraSettings {
        depth_factor: match sensor {
            SensorKind::Rgbd => Some(e.real_opt("DepthMapFactor")?.unwrap_or(5000.0)),
            SensorKind::Stereo => None,
        },
        rig,
        raw_pair: None,
        orb: e.orb(sensor)?,
        rgb: e.uint_opt("Camera.RGB")?.unwrap_or(1) != 0,
        camera,
    })
}

fn read_orbslam3(e: &Entries, sensor: SensorKind) -> Result<CameraSettings, DatasetError> {
    let kind = e
        .scalar("Camera.type")?
        .map(|(s, _)| s.to_string())
        .unwrap_or_else(|| "PinHole".into());
    let fps = e.real("Camera.fps")?;
    let (width, height) = e.size("Camera.width", "Camera.height")?;
    if width == 0 || height == 0 {
        return Err(DatasetError::invalid(
            e.path,
            "no `Camera.width` / `Camera.height` (required by ORB-SLAM3's format)",
        ));
    }
    let th_depth = e.real("Stereo.ThDepth")?;
    let intr = |p: &str| -> Result<[f64; 4], DatasetError> {
        Ok([
            e.real(&format!("{p}.fx"))?,
            e.real(&format!("{p}.fy"))?,
            e.real(&format!("{p}.cx"))?,
            e.real(&format!("{p}.cy"))?,
        ])
    };
    let [fx, fy, cx, cy] = intr("Camera1")?;
    let base = Camera {
        fx,
        fy,
        cx,
        cy,
        width,
        height,
        distortion: None,
        bf: 0.0,
        th_depth,
        fps,
        sensor,
    };
    let (camera, raw_pair) = match (kind.as_str(), sensor) {
        ("PinHole", SensorKind::Rgbd) => {
            let d = e.distortion("Camera1")?;
            (
                Camera {
                    distortion: (d != no_distortion()).then_some(d),
                    bf: e.real("Stereo.b")? * fx,
                    ..base
                },
                None,
            )
        }
        ("Rectified", SensorKind::Stereo) => (
            Camera {
                bf: e.real("Stereo.b")? * fx,
                ..base
            },
            None,
        ),
        ("PinHole", SensorKind::Stereo) => {
            let [fx2, fy2, cx2, cy2] = intr("Camera2")?;
            let t = e.matrix("Stereo.T_c1_c2", 4, 4)?;
            let m = Matrix4::from_row_slice(&t);
            let r3 = m.fixed_view::<3, 3>(0, 0).into_owned();
            let rot = crate::rectify::near_rotation(&r3).ok_or_else(|| {
                DatasetError::invalid(
                    e.path,
                    "`Stereo.T_c1_c2`: its rotation block is not a rotation",
                )
            })?;
            let t_c1_c2 = Isometry3::from_parts(
                Translation3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]),
                UnitQuaternion::from_rotation_matrix(&rot),
            );
            let left = raw_camera(
                width,
                height,
                &[fx, 0.0, cx, 0.0, fy, cy],
                e.distortion("Camera1")?,
                fps,
            );
            let mut right = raw_camera(
                width,
                height,
                &[fx2, 0.0, cx2, 0.0, fy2, cy2],
                e.distortion("Camera2")?,
                fps,
            );
            right.t_bs = t_c1_c2;
            // The rectified camera is computed when the pair is rectified.
            let rect = StereoRectification::new(&left, &right)
                .map_err(|err| DatasetError::invalid(e.path, err.to_string()))?;
            (rect.camera(th_depth), Some((left, right)))
        }
        (other, _) => {
            return Err(DatasetError::invalid(
                e.path,
                format!(
                    "Camera.type {other:?} is not supported for {} (noisefree reads PinHole, and \
                     Rectified for stereo)",
                    match sensor {
                        SensorKind::Rgbd => "RGB-D",
                        SensorKind::Stereo => "stereo",
                    }
                ),
            ))
        }
    };
    Ok(CameraSettings {
        camera,
        depth_factor: match sensor {
            SensorKind::Rgbd => Some(e.real_opt("RGBD.DepthMapFactor")?.unwrap_or(5000.0)),
            SensorKind::Stereo => None,
        },
        rig: None,
        raw_pair,
        orb: e.orb(sensor)?,
        rgb: e.uint_opt("Camera.RGB")?.unwrap_or(1) != 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reals_read_back_to_the_same_bits_and_carry_a_point() {
        for x in [
            40.0,
            517.306408,
            -0.000105,
            1.76187114e-05,
            435.2046959714599,
            0.1 + 0.2,
            1e-300,
        ] {
            let s = real(x);
            assert!(s.contains('.') || s.contains('e'), "{s}");
            assert_eq!(s.parse::<f64>().unwrap().to_bits(), x.to_bits(), "{s}");
        }
        assert_eq!(real(40.0), "40.0");
    }

    #[test]
    fn matrices_may_span_lines_and_comments_are_ignored() {
        let text = "%YAML:1.0\n# c\nA.K: !!opencv-matrix\n   rows: 2\n   cols: 2\n   dt: d\n   \
                    data:[1.0, 2.0, # first row\n      3, 4]\nB: \"x\" # q\n";
        let e = parse_entries(Path::new("f.yaml"), text).unwrap();
        assert_eq!(e.matrix("A.K", 2, 2).unwrap(), vec![1.0, 2.0, 3.0, 4.0]);
        assert_eq!(e.scalar("B").unwrap().unwrap().0, "x");
        let bad = "A.K: !!opencv-matrix\n   rows: 2\n   cols: 2\n   data: [1, 2, 3]\n";
        let err = parse_entries(Path::new("f.yaml"), bad)
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("f.yaml") && err.contains("3 values"), "{err}");
    }
}
