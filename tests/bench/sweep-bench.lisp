;;;; Sweep checks: one PR2 arm move in the kitchen (against checking its sub-step poses one by
;;;; one, the discrete alternative), and move-bottle under the default :WARN against no check.

(defpackage :cram-bench.sweep
  (:use :cl :cram-bench))

(in-package :cram-bench.sweep)

(load-tool "demo.lisp" :cram-plans-demo)

(defun median-of (values)
  (nth (floor (length values) 2) (sort (copy-list values) #'<)))

(defun arm-moves (n seed)
  "N seeded right-arm moves of the PR2 standing at the kitchen table, both ends clear of
everything: a list of (start-joints end-joints), every joint of the robot as DVECs."
  (let* ((robot (btr:get-robot-object))
         (w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle robot))
         (state (sb-ext:seed-random-state seed))
         (names (urdf-proj:arm-joint-names :right)))
    (flet ((random-clear ()
             (loop (btr:set-robot-state-from-joints
                    (loop for j in names
                          collect (multiple-value-bind (lo hi) (btr:joint-limits robot j)
                                    (let ((lo (or lo -3d0)) (hi (or hi 3d0)))
                                      (list j (+ lo (random (- hi lo) state))))))
                    robot)
                   (unless (urdf-proj:robot-collisions) (return (cram-native:robot-joints w r))))))
      (loop repeat n collect (list (random-clear) (random-clear))))))

(define-benchmark sweep-arm-move ()
  (let ((btr:*current-bullet-world* btr:*current-bullet-world*)
        (cpl:*log-stream* (make-broadcast-stream)))
    (btw-tut:init-projection)
    (let* ((robot (btr:get-robot-object))
           (w (btr:world-handle btr:*current-bullet-world*)) (r (btr:object-handle robot)))
      (setf (btr:pose robot) (cl-transforms:make-pose (cl-transforms:make-3d-vector -1.8547d0 -0.381d0 0)
                                                      (cl-transforms:axis-angle->quaternion
                                                       (cl-transforms:make-3d-vector 0 0 1) (/ pi -2))))
      (let* ((base (cram-native:object-pose w r))
             (moves (arm-moves 300 22))
             ;; the floor counts for no motion (as in the projection's checks)
             (ign (list (list -1 -1 (btr:object-handle (btr:object btr:*current-bullet-world* :floor)) -1)))
             (hits 0)
             (ours (median-of
                    (loop for (a b) in moves
                          collect (progn
                                    (when (cram-native:robot-sweep-check w r base a base b :ignore ign) (incf hits))
                                    (time-per-call (lambda () (cram-native:robot-sweep-check w r base a base b :ignore ign))
                                                   :min-seconds 0.002d0 :runs 3)))))
             (all (let ((v (make-array (length (first (first moves))) :element-type '(signed-byte 32))))
                    (dotimes (i (length v) v) (setf (aref v i) i))))
             ;; the discrete alternative: the move's sub-step poses (0.05 rad of summed joint
             ;; change apart), each set and checked for contacts
             (peer (median-of
                    (loop for (a b) in (subseq moves 0 60)
                          collect (let* ((n (max 1 (ceiling (loop for x across a for y across b sum (abs (- y x))) 0.05d0)))
                                         (q (make-array (length a) :element-type 'double-float)))
                                    (time-per-call
                                     (lambda ()
                                       (loop for k from 0 to n
                                             do (dotimes (i (length q))
                                                  (setf (aref q i) (+ (aref a i) (* (/ k n) (- (aref b i) (aref a i))))))
                                                (cram-native:set-robot-joints w r all q)
                                                (cram-native:object-contacts w r)))
                                     :min-seconds 0.002d0 :runs 3))))))
        (add-row (format nil "sweep check of one PR2 arm move at the kitchen table (median of 300 seeded moves, ~d hit something)" hits)
                 (format-seconds ours)
                 :peer-name "contacts at each of its 0.05 rad sub-step poses (misses what lies between)"
                 :peer (format-seconds peer) :ratio (/ ours peer)
                 :goal "<= 100 µs" :met (<= ours 100d-6))))))

(define-benchmark sweep-move-bottle ()
  ;; the runs alternate between the two settings (the machine's speed drifts over seconds)
  (let ((withouts '()) (withs '()))
    (dotimes (i 63)
      (let ((without (let ((urdf-proj:*sweep-check* nil)) (move-bottle-seconds)))
            (with (let ((urdf-proj:*sweep-check* :warn)) (move-bottle-seconds))))
        (when (>= i 3) (push without withouts) (push with withs))))
    (let ((with (median-of withs)) (without (median-of withouts)))
      (add-row "move-bottle with sweep checks (*sweep-check* :warn, the default), warm median (runs alternating with the peer's)"
               (format-seconds with)
               :peer-name "the same with *sweep-check* nil" :peer (format-seconds without)
               :ratio (/ with without) :goal "<= 1.15 x" :met (<= with (* 1.15 without))))))
