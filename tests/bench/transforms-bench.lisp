;;;; Transforms benchmarks: composition, point transformation and TF lookups, against tf2 (C++,
;;;; the library ROS uses) measured in the same run.

(require :asdf)
(asdf:load-asd (merge-pathnames "../../cram-plans.asd" *load-truename*))
(asdf:load-system "cram-plans/cl-transforms")

(defpackage :cram-bench.transforms
  (:use :cl :cram-bench))

(in-package :cram-bench.transforms)

(defparameter *chain*
  '("map" "odom_combined" "base_footprint" "base_link" "torso_lift_link" "r_shoulder_pan_link"
    "r_shoulder_lift_link" "r_upper_arm_roll_link" "r_elbow_flex_link" "r_forearm_roll_link"
    "r_wrist_flex_link" "r_wrist_roll_link" "r_gripper_tool_frame")
  "A PR2-like chain of frames from the map to the right tool frame (12 links).")

(defparameter *peer-source* "
#include <tf2/LinearMath/Transform.h>
#include <tf2/buffer_core.h>
#include <geometry_msgs/TransformStamped.h>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>
#include <algorithm>
using clk = std::chrono::steady_clock;
template <class F> double per_call(F f) {
  std::vector<double> runs;
  for (int r = 0; r < 7; ++r) {
    long n = 1;
    for (;;) {
      auto t0 = clk::now();
      for (long i = 0; i < n; ++i) f(i);
      double dt = std::chrono::duration<double>(clk::now() - t0).count();
      if (dt > 0.2) { runs.push_back(dt / n); break; }
      n *= 4;
    }
  }
  return *std::min_element(runs.begin(), runs.end());
}
int main(int argc, char** argv) {
  std::vector<std::string> chain(argv + 1, argv + argc);
  tf2::Transform a(tf2::Quaternion(0.1, 0.2, 0.3, 0.9).normalized(), tf2::Vector3(1, 2, 3));
  tf2::Transform b(tf2::Quaternion(-0.2, 0.1, 0.4, 0.8).normalized(), tf2::Vector3(-1, 0.5, 2));
  volatile double sink = 0;
  double compose = per_call([&](long i) { tf2::Transform c = a * b; b.getOrigin().setX(c.getOrigin().x() * 1e-9); sink += c.getOrigin().x(); });
  tf2::Vector3 p(0.3, -0.2, 1.0);
  double point = per_call([&](long i) { tf2::Vector3 q = a * p; p.setX(q.x() * 1e-9); sink += q.y(); });
  double inverse = per_call([&](long i) { tf2::Transform c = a.inverse(); a.getOrigin().setX(c.getOrigin().x() * 1e-9 + 1); sink += c.getOrigin().y(); });
  tf2::BufferCore buffer;
  auto make = [&](size_t k, double x) {
    geometry_msgs::TransformStamped t;
    t.header.frame_id = chain[k - 1]; t.child_frame_id = chain[k];
    t.header.stamp = ros::Time(1.0);
    t.transform.translation.x = x; t.transform.translation.y = 0.1; t.transform.translation.z = 0.05;
    t.transform.rotation.z = 0.0998334; t.transform.rotation.w = 0.995004;
    return t;
  };
  for (size_t k = 1; k < chain.size(); ++k) buffer.setTransform(make(k, 0.1 * k), \"bench\", true);
  double lookup = per_call([&](long i) {
    auto t = buffer.lookupTransform(chain.front(), chain.back(), ros::Time(0));
    sink += t.transform.translation.x; });
  double lookup_across = per_call([&](long i) {
    auto t = buffer.lookupTransform(chain.back(), chain[2], ros::Time(0));
    sink += t.transform.translation.x; });
  auto msg = make(3, 0.3);
  double set = per_call([&](long i) { buffer.setTransform(msg, \"bench\", true); });
  std::printf(\"compose %.12g\\npoint %.12g\\ninverse %.12g\\nlookup %.12g\\nlookup-across %.12g\\nset %.12g\\n\",
              compose, point, inverse, lookup, lookup_across, set);
  return sink == 12345.0;
}
")

(defun peer-times ()
  "Compile and run the tf2 peer; an alist (name . seconds per call), or NIL when it cannot run."
  (let* ((dir (uiop:ensure-directory-pathname
               (merge-pathnames "cram-plans-transforms-bench/" (uiop:temporary-directory))))
         (src (merge-pathnames "peer.cpp" dir))
         (exe (merge-pathnames "peer" dir)))
    (ensure-directories-exist dir)
    (with-open-file (s src :direction :output :if-exists :supersede)
      (write-string *peer-source* s))
    (let ((flags (run-peer "pkg-config" "--cflags" "--libs" "tf2")))
      (when (and flags
                 (run-peer "/bin/sh" "-c"
                           (format nil "g++ -O2 -o ~a ~a ~a"
                                   (namestring exe) (namestring src)
                                   (remove #\Newline flags))))
        (let ((out (apply #'run-peer (namestring exe) *chain*)))
          (when out
            (with-input-from-string (in out)
              (loop for line = (read-line in nil)
                    while line
                    collect (let ((sp (position #\Space line)))
                              (cons (subseq line 0 sp)
                                    (let ((*read-default-float-format* 'double-float))
                                      (float (read-from-string (subseq line (1+ sp)))
                                             1d0))))))))))))

(defun make-chain-transformer ()
  "A transformer holding *CHAIN* with the same transforms as the peer."
  (let ((tf (make-instance 'cl-tf:transformer)))
    (loop for (parent child) on *chain*
          for k from 1
          while child
          do (cl-tf:set-transform
              tf (cl-tf:make-transform-stamped parent child 1d0
                                               (cl-tf:make-3d-vector (* 0.1d0 k) 0.1d0 0.05d0)
                                               (cl-tf:make-quaternion 0 0 0.0998334d0 0.995004d0))
              :static t))
    tf))

(defun row (measure ours peers key goal-ratio)
  "Add a table row comparing OURS (seconds) with the peer's KEY time; met when within
GOAL-RATIO times the peer."
  (let ((peer (cdr (assoc key peers :test #'string=))))
    (add-row measure (format-seconds ours)
             :peer-name "tf2 0.7 (C++)"
             :peer (and peer (format-seconds peer))
             :ratio (and peer (/ ours peer))
             :goal (format nil "<= ~a x tf2" goal-ratio)
             :met (if peer (<= (/ ours peer) goal-ratio) :unknown))))

(defvar *sink* (make-array 1 :initial-element nil)
  "Where the timed forms store their results, so that no call can be optimised away.")

(defmacro per-call (form &key (runs 7) (min-seconds 0.2d0) (warmup-seconds 0.1d0))
  "Seconds per evaluation of FORM in steady state, measured like the peer's per_call: after a
warm-up of WARMUP-SECONDS, each of RUNS runs evaluates FORM in a loop of 1, 4, 16, ... iterations
until one loop takes longer than MIN-SECONDS; the result is the shortest of the runs' times per
iteration (the run least disturbed by other processes; garbage collection, which happens many
times in every run, stays included). FORM is compiled into the loop, as the peer's lambda is, so
no call through a closure is timed; its value is stored into *SINK*."
  (let ((loop-fn (gensym "LOOP")) (n (gensym "N")) (i (gensym "I")) (sink (gensym "SINK"))
        (start (gensym "START")))
    `(let ((,sink *sink*))
       (declare (type simple-vector ,sink))
       (flet ((,loop-fn (,n)
                (declare (type fixnum ,n))
                (let ((,start (now-seconds)))
                  (dotimes (,i ,n)
                    (declare (type fixnum ,i))
                    (setf (svref ,sink 0) ,form))
                  (- (now-seconds) ,start))))
         (declare (notinline ,loop-fn))
         (let ((,n 1))
           (declare (type fixnum ,n))
           (loop while (< (,loop-fn ,n) ,warmup-seconds) do (setf ,n (* ,n 4))))
         (let ((times (loop repeat ,runs
                            collect (let ((,n 1))
                                      (declare (type fixnum ,n))
                                      (loop for dt of-type double-float = (,loop-fn ,n)
                                            when (> dt ,min-seconds)
                                              return (/ dt ,n)
                                            do (setf ,n (* ,n 4)))))))
           (reduce #'min times))))))

(define-benchmark transforms ()
  (let* ((peers (peer-times))
         (a (cl-tf:make-transform (cl-tf:make-3d-vector 1 2 3)
                                  (cl-tf:make-quaternion 0.1d0 0.2d0 0.3d0 0.9d0)))
         (b (cl-tf:make-transform (cl-tf:make-3d-vector -1 0.5d0 2)
                                  (cl-tf:make-quaternion -0.2d0 0.1d0 0.4d0 0.8d0)))
         (p (cl-tf:make-3d-vector 0.3d0 -0.2d0 1))
         (tf (make-chain-transformer))
         (first-frame (first *chain*))
         (last-frame (car (last *chain*)))
         (third-frame (third *chain*))
         (update (cl-tf:make-transform-stamped (third *chain*) (fourth *chain*) 1d0
                                               (cl-tf:make-3d-vector 0.3d0 0.1d0 0.05d0)
                                               (cl-tf:make-identity-rotation))))
    (row "transform* (compose two transforms)"
         (per-call (cl-tf:transform* a b)) peers "compose" 3)
    (row "transform-point"
         (per-call (cl-tf:transform-point a p)) peers "point" 3)
    (row "transform-inv"
         (per-call (cl-tf:transform-inv a)) peers "inverse" 3)
    (row "lookup-transform map -> tool frame (12 links)"
         (per-call (cl-tf:lookup-transform tf first-frame last-frame)) peers "lookup" 1)
    (row "lookup-transform tool frame -> base (across, 10 links)"
         (per-call (cl-tf:lookup-transform tf last-frame third-frame)) peers "lookup-across" 1)
    (row "set-transform"
         (per-call (cl-tf:set-transform tf update :static t)) peers "set" 1)
    (svref *sink* 0)))
