//! A map point's frame views (`data::FrameViews`, MC-OR's every-frame reading) as cluster
//! features: each view placed through its reference keyframe's current pose, so a view moves
//! with the keyframe when bundle adjustment or a loop correction moves it.

use nalgebra::{Isometry3, Point3};

use super::cluster::{ClusterFeature, McorCluster};
use crate::data::{FrameView, FrameViews, FRAME_VIEW_SOURCE_BIT};
use crate::ids::KeyFrameId;

impl ClusterFeature {
    /// Frame view `view` as a cluster feature, placed through its reference keyframe's pose
    /// `tkw` (world to camera) when known, else where it was stored.
    pub fn of_view(view: &FrameView, tkw: Option<&Isometry3<f64>>) -> ClusterFeature {
        Self::of_view_placed_by(view, tkw.map(|t| t.inverse()).as_ref())
    }

    /// As [`of_view`](Self::of_view), given the inverse `twk` (keyframe to world) of the
    /// reference keyframe's pose: for callers placing many views with one keyframe.
    pub fn of_view_placed_by(view: &FrameView, twk: Option<&Isometry3<f64>>) -> ClusterFeature {
        let world = match twk {
            Some(t) => (t * Point3::from(view.point_reference)).coords,
            None => view.point_world,
        };
        ClusterFeature::placed(FRAME_VIEW_SOURCE_BIT | view.frame, view.point_camera, world)
    }
}

impl McorCluster {
    /// Adds a map point's frame views after its keyframe features: the folded sum, then each
    /// view placed with its reference keyframe's current pose `tkw_of(reference)` (world to
    /// camera).
    pub fn extend_with_views(
        &mut self,
        views: &FrameViews,
        mut tkw_of: impl FnMut(KeyFrameId) -> Option<Isometry3<f64>>,
    ) {
        let (sum, count) = views.folded();
        self.add_folded(sum, count);
        for v in views.views() {
            let tkw = tkw_of(v.reference);
            self.push_distinct(ClusterFeature::of_view(v, tkw.as_ref()));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::MCOR_CLUSTER_CAPACITY;
    use nalgebra::{Translation3, UnitQuaternion, Vector3};

    fn pose(x: f64, yaw: f64) -> Isometry3<f64> {
        Isometry3::from_parts(
            Translation3::new(x, 0.2, -0.1),
            UnitQuaternion::from_euler_angles(0.0, 0.1, yaw),
        )
    }

    #[test]
    fn a_view_follows_its_reference_keyframe() {
        let tcw = pose(0.3, 0.2);
        let tkw = pose(0.1, -0.1);
        let p = Vector3::new(0.2, -0.1, 1.7);
        let v = FrameView::new(7, &tcw, KeyFrameId(3), &tkw, p).unwrap();
        let world = (tcw.inverse() * Point3::from(p)).coords;
        assert!((ClusterFeature::of_view(&v, Some(&tkw)).point_world() - world).norm() < 1e-12);
        // The keyframe moves by a correction C (new Twk = C * Twk): the view moves with it.
        let c = pose(0.5, 0.4);
        let tkw_new = tkw * c.inverse();
        let moved = ClusterFeature::of_view(&v, Some(&tkw_new)).point_world();
        assert!((moved - (c * Point3::from(world)).coords).norm() < 1e-12);
        // Its keyframe gone, it stays where it was stored; its depth is the frame's.
        assert_eq!(ClusterFeature::of_view(&v, None).point_world(), world);
        assert_eq!(ClusterFeature::of_view(&v, None).depth(), 1.7);
        assert!(
            FrameView::new(1, &tcw, KeyFrameId(0), &tkw, Vector3::new(0.0, 0.0, -1.0)).is_none()
        );
    }

    #[test]
    fn views_are_bounded_and_the_centroid_counts_every_view() {
        let id = Isometry3::identity();
        let mut views = FrameViews::default();
        let n = MCOR_CLUSTER_CAPACITY + 8;
        for f in 0..n {
            let p = Vector3::new(f as f64, 0.0, 1.0);
            views.push(FrameView::new(f as u64, &id, KeyFrameId(0), &id, p).unwrap());
        }
        assert_eq!(views.views().len(), MCOR_CLUSTER_CAPACITY);
        assert_eq!(views.total_count(), n as u64);
        assert_eq!(views.views().next().unwrap().frame, 8);
        let mut cluster = McorCluster::new();
        cluster.extend_with_views(&views, |_| Some(id));
        assert_eq!(cluster.total_count(), n as u64);
        let mean_x = (0..n).map(|f| f as f64).sum::<f64>() / n as f64;
        assert!((cluster.centroid().unwrap().x - mean_x).abs() < 1e-12);
    }
}
