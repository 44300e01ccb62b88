;;;; Tests of the TF transformer (frame tree lookups, errors, threads) and of CRAM-TF.

(in-package :cram-plans-tests.transforms)

(in-suite transforms)

(defun q-yaw (degrees)
  "The rotation by DEGREES about z."
  (axis-angle->quaternion (make-3d-vector 0 0 1) (* degrees (/ pi 180))))

(defun make-test-tree (&key (stamps '(5 7 3)))
  "A transformer holding the tree
    map -> odom_combined   (1 2 0), yaw 90
    odom_combined -> base_footprint   (1 0 0), no rotation
    map -> table   (-1 0 0.5), yaw 180, static."
  (let ((tf (make-instance 'cl-tf:transformer)))
    (cl-tf:set-transform tf (make-transform-stamped "map" "odom_combined" (first stamps)
                                                    (make-3d-vector 1 2 0) (q-yaw 90)))
    (cl-tf:set-transform tf (make-transform-stamped "odom_combined" "base_footprint"
                                                    (second stamps)
                                                    (make-3d-vector 1 0 0)
                                                    (make-identity-rotation)))
    (cl-tf:set-transform tf (make-transform-stamped "map" "table" (third stamps)
                                                    (make-3d-vector -1 0 0.5) (q-yaw 180))
                         :static t)
    tf))

(defun close-transform-p (transform translation yaw-degrees &optional (tolerance 1d-12))
  "True when TRANSFORM has the TRANSLATION (a list) and a rotation of YAW-DEGREES about z."
  (and (v= (translation transform) (apply #'make-3d-vector translation) tolerance)
       (< (angle-between-quaternions (rotation transform) (q-yaw yaw-degrees)) tolerance)))

(defun close-pose-p (pose origin yaw-degrees &optional (tolerance 1d-12))
  "True when POSE has ORIGIN (a list) and an orientation of YAW-DEGREES about z."
  (close-transform-p (pose->transform pose) origin yaw-degrees tolerance))

(test tf-lookups-up-down-and-across
  (let ((tf (make-test-tree)))
    ;; up: base_footprint in map
    (let ((tr (lookup-transform tf "map" "base_footprint")))
      (is (typep tr 'transform-stamped))
      (is (string= "map" (frame-id tr)))
      (is (string= "base_footprint" (child-frame-id tr)))
      (is (close-transform-p tr '(1 3 0) 90)))
    ;; down: map in base_footprint
    (is (close-transform-p (lookup-transform tf "base_footprint" "map") '(-3 1 0) -90))
    ;; across the root: base_footprint in table, table in odom_combined
    (is (close-transform-p (lookup-transform tf "table" "base_footprint") '(-2 -3 -0.5) -90))
    (is (close-transform-p (lookup-transform tf "odom_combined" "table") '(-2 2 0.5) 90))
    ;; one step and identity
    (is (close-transform-p (lookup-transform tf "odom_combined" "base_footprint") '(1 0 0) 0))
    (is (close-transform-p (lookup-transform tf "table" "table") '(0 0 0) 0))
    ;; leading slashes name the same frames
    (is (close-transform-p (lookup-transform tf "/map" "/base_footprint") '(1 3 0) 90))
    ;; a lookup and its reverse are inverses
    (is (< (transform-error (transform* (lookup-transform tf "table" "base_footprint")
                                        (lookup-transform tf "base_footprint" "table"))
                            (make-identity-transform))
           1d-12))))

(test tf-lookup-stamps
  (let ((tf (make-test-tree :stamps '(5 7 3))))
    ;; the oldest non-static stamp along the path
    (is (= 5d0 (stamp (lookup-transform tf "map" "base_footprint"))))
    (is (= 7d0 (stamp (lookup-transform tf "odom_combined" "base_footprint"))))
    ;; static transforms do not limit the stamp; a path of static ones has stamp 0
    (is (= 5d0 (stamp (lookup-transform tf "table" "base_footprint"))))
    (is (= 0d0 (stamp (lookup-transform tf "map" "table"))))
    ;; an explicit time becomes the stamp
    (is (= 42d0 (stamp (lookup-transform tf "map" "base_footprint" :time 42))))))

(test tf-transform-pose-and-point-stamped
  (let ((tf (make-test-tree)))
    (let ((p (transform-pose-stamped
              tf :target-frame "table"
                 :pose (make-pose-stamped "base_footprint" 1.5 (make-3d-vector 1 0 0)
                                          (make-identity-rotation)))))
      (is (typep p 'pose-stamped))
      (is (string= "table" (frame-id p)))
      (is (= 1.5d0 (stamp p)))
      (is (close-pose-p p '(-2 -4 -0.5) -90)))
    (let ((p (cl-tf:transform-pose-stamped
              tf :target-frame "map" :timeout 0.1
                 :pose (make-pose-stamped "table" 0 (make-3d-vector 0 0 0)
                                          (make-identity-rotation)))))
      (is (close-pose-p p '(-1 0 0.5) 180)))
    (let ((p (transform-point-stamped
              tf :target-frame "map"
                 :point (make-point-stamped "base_footprint" 0 (make-3d-vector 1 0 0)))))
      (is (typep p 'point-stamped))
      (is (string= "map" (frame-id p)))
      (is (v= p (make-3d-vector 1 4 0) 1d-12)))))

(test tf-errors-name-the-frames
  (let ((tf (make-test-tree)))
    (cl-tf:set-transform tf (make-transform-stamped "other_root" "island" 0
                                                    (make-identity-vector)
                                                    (make-identity-rotation)))
    (is (can-transform tf "map" "base_footprint"))
    (is (not (can-transform tf "map" "island")))
    (is (not (can-transform tf "map" "no_such_frame")))
    (let ((e (handler-case (lookup-transform tf "map" "no_such_frame")
               (error (e) e))))
      (is (typep e 'cl-tf:tf-lookup-error))
      (is (typep e 'cl-tf:transform-stamped-error))
      (is (search "\"no_such_frame\"" (princ-to-string e))))
    (let ((e (handler-case (lookup-transform tf "no_such_target" "map")
               (error (e) e))))
      (is (typep e 'cl-tf:tf-lookup-error))
      (is (search "no_such_target" (princ-to-string e))))
    (let ((e (handler-case (lookup-transform tf "map" "island")
               (error (e) e))))
      (is (typep e 'cl-tf:tf-connectivity-error))
      (is (search "\"island\"" (princ-to-string e)))
      (is (search "\"map\"" (princ-to-string e))))
    (let ((e (handler-case (transform-pose-stamped
                            tf :target-frame "ghost"
                               :pose (make-pose-stamped "map" 0 (make-identity-vector)
                                                        (make-identity-rotation)))
               (error (e) e))))
      (is (typep e 'cl-tf:tf-lookup-error))
      (is (search "ghost" (princ-to-string e))))
    ;; bad arguments
    (is (search "42" (error-message (lambda () (lookup-transform tf 42 "map")))))
    (is (search "FOO" (error-message (lambda () (lookup-transform 'foo "map" "table")))))
    (is (search "\"\"" (error-message (lambda () (lookup-transform tf "" "map")))))
    (is (search "#<POSE" (error-message
                          (lambda () (transform-pose-stamped tf :target-frame "map"
                                                                :pose (make-identity-pose))))))
    (is (search "transform between two different frames"
                (error-message (lambda () (cl-tf:set-transform
                                           tf (make-transform-stamped
                                               "map" "/map" 0 (make-identity-vector)
                                               (make-identity-rotation)))))))
    ;; closing a loop is refused and leaves the tree as it was
    (is (typep (handler-case (cl-tf:set-transform
                              tf (make-transform-stamped "base_footprint" "map" 0
                                                         (make-identity-vector)
                                                         (make-identity-rotation)))
                 (error (e) e))
               'cl-tf:tf-connectivity-error))
    (is (close-transform-p (lookup-transform tf "map" "base_footprint") '(1 3 0) 90))))

(test tf-reparenting-and-clear
  (let ((tf (make-test-tree)))
    ;; move table under base_footprint
    (cl-tf:set-transform tf (make-transform-stamped "base_footprint" "table" 9
                                                    (make-3d-vector 1 0 0) (q-yaw 0)))
    (is (close-transform-p (lookup-transform tf "map" "table") '(1 4 0) 90))
    (is (equal '("base_footprint" "map" "odom_combined" "table") (cl-tf:known-frames tf)))
    (is (cl-tf:frame-exists tf "/odom_combined"))
    ;; the map -> odom_combined link is the only static-free one left after... set it static
    (cl-tf:set-transform tf (make-transform-stamped "map" "odom_combined" 1
                                                    (make-3d-vector 1 2 0) (q-yaw 90))
                         :static t)
    (clear tf)
    (is (equal '("map" "odom_combined") (cl-tf:known-frames tf)))
    (is (can-transform tf "odom_combined" "map"))
    (is (not (can-transform tf "map" "base_footprint")))
    (clear tf :static t)
    (is (null (cl-tf:known-frames tf)))))

(test tf-lookup-waits-for-a-late-transform
  (let* ((tf (make-test-tree))
         (writer (bt:make-thread
                  (lambda ()
                    (sleep 0.05)
                    (cl-tf:set-transform tf (make-transform-stamped
                                             "base_footprint" "late_frame" 0
                                             (make-3d-vector 0 0 1) (make-identity-rotation))))
                  :name "late tf writer")))
    (is (close-transform-p (lookup-transform tf "map" "late_frame" :timeout 5) '(1 3 1) 90))
    (bt:join-thread writer))
  ;; without the transform, the lookup gives up after its timeout
  (let ((tf (make-test-tree))
        (start (get-internal-real-time)))
    (is (typep (handler-case (lookup-transform tf "map" "never_frame" :timeout 0.1)
                 (error (e) e))
               'cl-tf:tf-lookup-error))
    (is (>= (/ (- (get-internal-real-time) start) internal-time-units-per-second) 0.09))))

(test tf-concurrent-updates-and-lookups
  ;; one thread moves base_footprint along x while this one looks it up: every answer must be
  ;; one of the consistent states, never a torn or failed one
  (let* ((tf (make-test-tree :stamps '(100000 1 0)))
         (n 3000)
         (reading nil)
         (writer (bt:make-thread
                  (lambda ()
                    ;; start writing only once the reader runs, so the two overlap
                    (loop until reading do (bt:thread-yield))
                    (dotimes (i n)
                      (cl-tf:set-transform tf (make-transform-stamped
                                               "odom_combined" "base_footprint" i
                                               (make-3d-vector i 0 0)
                                               (make-identity-rotation)))))
                  :name "tf writer"))
         (bad 0) (looked 0))
    (setf reading t)
    (loop do (let* ((tr (lookup-transform tf "map" "base_footprint"))
                    (k (stamp tr)))
               (incf looked)
               ;; base in map is (1, 2 + k, 0) with the stamp k of the odom link
               (unless (close-transform-p tr (list 1 (+ 2 k) 0) 90 1d-9)
                 (incf bad)))
          while (bt:thread-alive-p writer))
    (bt:join-thread writer)
    (is (plusp looked))
    (is (zerop bad) "~d of ~d lookups were inconsistent" bad looked)
    (is (close-transform-p (lookup-transform tf "map" "base_footprint")
                           (list 1 (+ 2 (1- n)) 0) 90 1d-9))))

(test tf-batch-updates-are-seen-whole
  ;; a writer moves odom_combined and base_footprint together, as one batch, so that the base
  ;; stays at (1 2 0) in the map; a reader in another thread must never see half a batch
  (let* ((tf (let ((tf (make-test-tree)))
               (cl-tf:set-transform tf (make-transform-stamped
                                        "odom_combined" "base_footprint" 0
                                        (make-3d-vector 0 0 0) (make-identity-rotation)))
               tf))
         (n 2000)
         (reading nil)
         (writer (bt:make-thread
                  (lambda ()
                    (loop until reading do (bt:thread-yield))
                    (dotimes (i n)
                      (cl-tf:with-transforms-batch (tf)
                        ;; odom at (1, 2 + i) in map (yaw 90); base at (-i, 0) in odom: x of odom
                        ;; points along y of the map, so the base stays at (1 2 0)
                        (cl-tf:set-transform tf (make-transform-stamped
                                                 "map" "odom_combined" i
                                                 (make-3d-vector 1 (+ 2 i) 0) (q-yaw 90)))
                        (bt:thread-yield)
                        (cl-tf:set-transform tf (make-transform-stamped
                                                 "odom_combined" "base_footprint" i
                                                 (make-3d-vector (- i) 0 0)
                                                 (make-identity-rotation))))))
                  :name "tf batch writer"))
         (bad 0) (looked 0))
    (setf reading t)
    (loop do (let ((tr (lookup-transform tf "map" "base_footprint")))
               (incf looked)
               (unless (close-transform-p tr (list 1 2 0) 90 1d-6)
                 (incf bad)))
          while (bt:thread-alive-p writer))
    (bt:join-thread writer)
    (is (plusp looked))
    (is (zerop bad) "~d of ~d lookups saw half a batch" bad looked)))

(test tf-deferred-updates
  ;; an update put off with DEFER-UPDATE runs once, when the transformer is next read or
  ;; written, and before what that reader or writer does
  (let* ((tf (make-test-tree))
         (runs 0)
         (update (lambda ()
                   (incf runs)
                   (cl-tf:set-transform tf (make-transform-stamped
                                            "odom_combined" "base_footprint" 8
                                            (make-3d-vector 2 0 0) (make-identity-rotation))))))
    (is (eq tf (cl-tf:defer-update tf update)))
    (is (= 0 runs))
    (is (close-transform-p (lookup-transform tf "map" "base_footprint") '(1 4 0) 90))
    (is (= 1 runs))
    (lookup-transform tf "map" "base_footprint")
    (is (= 1 runs))
    ;; a later deferred update replaces one that has not run
    (cl-tf:defer-update tf (lambda () (incf runs 10)))
    (cl-tf:defer-update tf update)
    (is (cl-tf:frame-exists tf "base_footprint"))
    (is (= 2 runs))
    ;; a transform set after the deferral wins over the deferred one
    (cl-tf:defer-update tf update)
    (cl-tf:set-transform tf (make-transform-stamped "odom_combined" "base_footprint" 9
                                                    (make-3d-vector 3 0 0)
                                                    (make-identity-rotation)))
    (is (= 3 runs))
    (is (close-transform-p (lookup-transform tf "map" "base_footprint") '(1 5 0) 90))
    ;; CLEAR and KNOWN-FRAMES see the deferred transforms too
    (cl-tf:defer-update tf (lambda () (cl-tf:set-transform tf (make-transform-stamped
                                                               "base_footprint" "hand" 1
                                                               (make-3d-vector 0 0 1)
                                                               (make-identity-rotation)))))
    (is (member "hand" (cl-tf:known-frames tf) :test #'string=))
    (cl-tf:defer-update tf (lambda () (incf runs 100)))
    (clear tf :static t)
    (is (= 103 runs))
    (is (null (cl-tf:known-frames tf)))
    ;; a lookup already waiting for a frame gets a deferred update at once
    (let* ((tf (make-test-tree))
           (reader (bt:make-thread (lambda () (lookup-transform tf "map" "late_frame" :timeout 5))
                                   :name "waiting tf reader")))
      (loop until (plusp (cl-transforms-stamped::transformer-waiters tf)) do (sleep 0.001))
      (cl-tf:defer-update tf (lambda ()
                               (cl-tf:set-transform tf (make-transform-stamped
                                                        "base_footprint" "late_frame" 0
                                                        (make-3d-vector 0 0 1)
                                                        (make-identity-rotation)))))
      (is (close-transform-p (bt:join-thread reader) '(1 3 1) 90)))
    (is (typep (handler-case (cl-tf:defer-update tf 42) (error (e) e))
               'cl-transforms:transform-input-error))))

;;; Stamped objects

(test stamped-constructors-and-copies
  (let ((ps (cl-transforms-stamped:make-pose-stamped "/map" 0 (make-3d-vector 1 2 3)
                                                     (make-identity-rotation))))
    (is (string= "map" (frame-id ps)))
    (is (= 0d0 (stamp ps)))
    (let ((c (copy-pose-stamped ps :frame-id "odom_combined" :stamp 3)))
      (is (string= "odom_combined" (frame-id c)))
      (is (= 3d0 (stamp c)))
      (is (equalp (origin ps) (origin c))))
    (let ((c (copy-pose-stamped ps :origin (make-3d-vector 4 5 6))))
      (is (string= "map" (frame-id c)))
      (is (equalp (make-3d-vector 4 5 6) (origin c)))))
  (let ((ps (pose->pose-stamped "map" 0 '((1 2 3) (0 0 0 1)))))
    (is (equalp (make-3d-vector 1 2 3) (origin ps))))
  (let ((ts (transform->transform-stamped "a" "b" 2 (make-transform (make-3d-vector 1 0 0)
                                                                    (q-yaw 30)))))
    (is (string= "b" (child-frame-id ts)))
    (is (string= "c" (child-frame-id (copy-transform-stamped ts :child-frame-id "c"))))
    (is (equalp (make-3d-vector 1 0 0) (translation (transform-stamped->transform ts))))))

;;; CRAM-TF

(defmacro with-test-transformer ((var) &body body)
  "Run BODY with cram-tf:*transformer* bound to a fresh test tree, also bound to VAR."
  `(let* ((,var (make-test-tree))
          (cram-tf:*transformer* ,var)
          (cram-tf:*tf-default-timeout* 0))
     (declare (ignorable ,var))
     ,@body))

(test cram-tf-robot-current-pose
  (with-test-transformer (tf)
    (is (string= "map" cram-tf:*fixed-frame*))
    (is (string= "base_footprint" cram-tf:*robot-base-frame*))
    (is (string= "odom_combined" cram-tf:*odom-frame*))
    (let ((p (cram-tf:robot-current-pose)))
      (is (typep p 'pose-stamped))
      (is (string= "map" (frame-id p)))
      (is (close-pose-p p '(1 3 0) 90)))
    (is (close-pose-p (cram-tf:frame-to-pose-in-fixed-frame "table") '(-1 0 0.5) 180)))
  (let ((cram-tf:*transformer* (make-instance 'cl-tf:transformer))
        (cram-tf:*tf-default-timeout* 0))
    (is (typep (handler-case (cram-tf:robot-current-pose) (error (e) e))
               'cl-tf:tf-lookup-error))))

(test cram-tf-rotate-and-translate
  (let* ((p (make-pose-stamped "map" 2 (make-3d-vector 1 2 3) (q-yaw 30)))
         (r (cram-tf:rotate-pose p :z (/ pi 3)))
         (m (cram-tf:translate-pose p :x-offset 1 :z-offset -0.5)))
    (is (typep r 'pose-stamped))
    (is (string= "map" (frame-id r)))
    (is (= 2d0 (stamp r)))
    (is (close-pose-p r '(1 2 3) 90))
    (is (typep m 'pose-stamped))
    (is (close-pose-p m '(2 2 2.5) 30)))
  ;; rotation about the reference frame's axes: x turns the yawed frame's orientation first
  (let ((r (cram-tf:rotate-pose (make-pose (make-3d-vector 0 0 0) (q-yaw 90)) :x (/ pi 2))))
    (is (typep r 'pose))
    (is (not (typep r 'pose-stamped)))
    (is (< (v-dist (rotate (orientation r) (make-3d-vector 1 0 0)) (make-3d-vector 0 0 1))
           1d-12)))
  (is (search ":W" (error-message (lambda () (cram-tf:rotate-pose (make-identity-pose) :w 1))))))

(test cram-tf-conversions
  (let* ((ps (make-pose-stamped "map" 4 (make-3d-vector 1 2 3) (q-yaw 45)))
         (ts (cram-tf:pose-stamped->transform-stamped ps "robot")))
    (is (string= "map" (frame-id ts)))
    (is (string= "robot" (child-frame-id ts)))
    (is (= 4d0 (stamp ts)))
    (is (equalp (origin ps) (translation ts)))
    (is (equalp ps (cram-tf:transform-stamped->pose-stamped ts)))
    (let ((inv (cram-tf:transform-stamped-inv ts)))
      (is (string= "robot" (frame-id inv)))
      (is (string= "map" (child-frame-id inv)))
      (is (close-transform-p (cram-tf:apply-transform ts inv) '(0 0 0) 0)))
    (is (search "\"robot\""
                (error-message (lambda () (cram-tf:multiply-transform-stampeds
                                           "map" "robot" ts ts))))))
  (let ((l '((1.0d0 2.0d0 3.0d0) (0.0d0 0.0d0 0.0d0 1.0d0))))
    (is (equal l (cram-tf:pose->list (cram-tf:list->pose l))))
    (is (equal '(1d0 2d0 3d0 0d0 0d0 0d0 1d0)
               (cram-tf:pose->flat-list (cram-tf:flat-list->pose '(1 2 3 0 0 0 1)))))
    (is (equal '(1d0 2d0 3d0 1d0 0d0 0d0 0d0)
               (cram-tf:pose->flat-list-w-first (cram-tf:list->pose l))))
    (is (equal (list "map" 0d0 l)
               (cram-tf:pose-stamped->list (cram-tf:list->pose-stamped (list "map" 0 l))))))
  (is (search "(1 2 3)" (error-message (lambda () (cram-tf:list->pose '(1 2 3)))))))

(test cram-tf-ensure-in-frame
  (with-test-transformer (tf)
    (let ((p (cram-tf:ensure-pose-in-frame
              (make-pose-stamped "base_footprint" 0 (make-3d-vector 1 0 0)
                                 (make-identity-rotation))
              "table")))
      (is (close-pose-p p '(-2 -4 -0.5) -90)))
    ;; a plain pose is taken to be in the frame already
    (let ((p (cram-tf:ensure-pose-in-frame (make-pose (make-3d-vector 1 2 3) (q-yaw 10)) "map")))
      (is (string= "map" (frame-id p)))
      (is (close-pose-p p '(1 2 3) 10)))
    (is (null (cram-tf:ensure-pose-in-frame nil "map")))
    (let ((pt (cram-tf:ensure-point-in-frame
               (make-point-stamped "base_footprint" 0 (make-3d-vector 1 0 0)) "map")))
      (is (v= pt (make-3d-vector 1 4 0) 1d-12)))
    (is (cram-tf:poses-equal-p (cram-tf:robot-current-pose)
                               (make-pose-stamped "map" 0 (make-3d-vector 1 3.001 0) (q-yaw 91))
                               0.01 0.02))
    (is (not (cram-tf:poses-equal-p (cram-tf:robot-current-pose)
                                    (make-pose-stamped "map" 0 (make-3d-vector 1 3 0) (q-yaw 95))
                                    0.01 0.02)))
    (is (cram-tf:tf-frame-converged "base_footprint"
                                    (make-pose-stamped "map" 0 (make-3d-vector 1 3.01 0)
                                                       (q-yaw 90.5))
                                    0.02 0.01))))

(test seed-shelf-and-robot-pose-snippets
  ;; the pose arithmetic of the Pepper shop tutorial, written as the seed writes it
  (with-test-transformer (tf)
    (let* ((offset (cl-tf:make-transform (cl-tf:make-3d-vector -0.3 0.0 0.0)
                                         (cl-tf:make-quaternion 0 0 0 1)))
           (robot-cur-pose (cram-tf:robot-current-pose))
           (robot-cur-trans (cl-transforms:pose->transform robot-cur-pose))
           (new-pose (cl-transforms-stamped:pose->pose-stamped
                      "map" 0 (cl-transforms:transform->pose
                               (cl-transforms:transform* robot-cur-trans offset)))))
      ;; 0.3 m behind a robot at (1 3) facing +y
      (is (close-pose-p new-pose '(1 2.7 0) 90 1d-9))
      ;; turning the robot towards a target, as calculate-pose-towards-target does
      (let* ((look (cl-transforms-stamped:make-pose-stamped
                    "map" 0.0 (cl-transforms:make-3d-vector 0 3 1)
                    (cl-transforms:make-identity-rotation)))
             (world->robot (cram-tf:pose-stamped->transform-stamped robot-cur-pose "robot"))
             (robot->world (cl-transforms:transform-inv world->robot))
             (in-robot (cl-transforms:transform-point robot->world (cl-transforms:origin look)))
             (angle (atan (cl-transforms:y in-robot) (cl-transforms:x in-robot)))
             (turned (cram-tf:rotate-pose robot-cur-pose :z angle)))
        ;; the target is straight to the robot's left: turn a quarter to face -x
        (is (< (abs (- angle (/ pi 2))) 1d-9))
        (is (close-pose-p turned '(1 3 0) 180 1d-9))))))
