;;;; Tests of more of CRAM's BTR API: STEP is CL:STEP, attachments of lists and between items,
;;;; WITH-CURRENT-BULLET-WORLD, PROLOG-?W, CLEAR-BULLET-WORLD, OBJ-POSE-ON, bounding boxes,
;;;; ROBOT-ATTACHED-OBJECTS-IN-COLLISION, timelines, GENERATE-URDF-STRING.

(defpackage :cram-btr-api-tests
  (:use :cl :fiveam)
  (:import-from :cram-prolog #:prolog)
  (:import-from :cram-utilities #:force-ll #:var-value))

(in-package :cram-btr-api-tests)

(def-suite btr-api :in cram-plans-tests:all :description "More of CRAM's BTR API.")
(in-suite btr-api)

(defun small-world ()
  "A new current world with a table and two boxes on it."
  (let ((w (make-instance 'btr:bt-reasoning-world)))
    (setf btr:*current-bullet-world* w)
    (btr:add-object w :box 'table '((0 0 0.35) (0 0 0 1)) :size '(1 1 0.7))
    (btr:add-object w :box 'tray '((0 0 0.72) (0 0 0 1)) :size '(0.3 0.3 0.04) :mass 0.5)
    (btr:add-object w :box 'cup '((0 0 0.79) (0 0 0 1)) :size '(0.06 0.06 0.1) :mass 0.1)
    w))

(defun x-of (object) (cl-transforms:x (cl-transforms:origin (btr:pose object))))

(defparameter *arm-urdf*
  "<robot name=\"arm\">
     <link name=\"base\"><collision><geometry><box size=\"0.1 0.1 0.1\"/></geometry></collision></link>
     <link name=\"hand\"><collision><geometry><box size=\"0.05 0.05 0.05\"/></geometry></collision></link>
     <joint name=\"lift\" type=\"prismatic\"><parent link=\"base\"/><child link=\"hand\"/>
       <origin xyz=\"0 0 0.3\" rpy=\"0 0 0\"/><axis xyz=\"0 0 1\"/>
       <limit lower=\"-0.5\" upper=\"0.5\" velocity=\"1\" effort=\"10\"/></joint>
   </robot>")

(test btr-and-common-lisp-together
  (is (eq 'cl:step (find-symbol "STEP" :btr)))
  (let ((package (make-package (gensym "BTR-USER") :use '(:cl :btr))))
    (unwind-protect (is (eq 'btr:object (find-symbol "OBJECT" package)))
      (delete-package package)))
  (small-world)
  (let ((before (cl-transforms:z (cl-transforms:origin (btr:pose (btr:object btr:*current-bullet-world* 'cup))))))
    (is (= 1 (length (force-ll (prolog '(and (btr:bullet-world ?w) (step ?w)))))))
    (is (numberp before))))

(test attach-object-with-lists-and-nil
  (let* ((w (small-world))
         (tray (btr:object w 'tray)) (cup (btr:object w 'cup)) (table (btr:object w 'table)))
    (signals warning (btr:attach-object nil cup))
    (is (null (handler-bind ((warning #'muffle-warning)) (btr:attach-object nil cup))))
    (is (null (btr:attached-objects cup)))
    (btr:attach-object (list tray table) cup)
    (is (equal '(tray table) (mapcar #'first (btr:attached-objects cup))))
    (is (equal '(cup) (mapcar #'first (btr:attached-objects tray))))
    (is (equal '(cup) (mapcar #'first (btr:attached-objects table))))
    (btr:detach-object tray cup)
    (is (equal '(table) (mapcar #'first (btr:attached-objects cup))))
    (btr:detach-all-objects table)
    (is (null (btr:attached-objects cup)))
    (is (equal '() (btr:attach-object tray '())) "an empty list of objects attaches nothing")))

(test item-attachments-move-the-attached-item
  (let* ((w (small-world))
         (tray (btr:object w 'tray)) (cup (btr:object w 'cup)))
    (btr:attach-object tray cup)
    (is (equal '((cup nil)) (btr:attached-objects tray)))
    (setf (btr:pose tray) (cl-transforms:make-pose (cl-transforms:make-3d-vector 0.2 0 0.72)
                                                   (cl-transforms:make-identity-rotation)))
    (is (< (abs (- 0.2 (x-of cup))) 1d-6) "the cup follows the tray")
    (btr:detach-object tray cup)
    (setf (btr:pose tray) (cl-transforms:make-pose (cl-transforms:make-3d-vector -0.2 0 0.72)
                                                   (cl-transforms:make-identity-rotation)))
    (is (< (abs (- 0.2 (x-of cup))) 1d-6) "a detached cup stays")))

(test current-world-macros-and-predicates
  (let ((w (small-world)) (other (make-instance 'btr:bt-reasoning-world)))
    (btr:with-current-bullet-world other
      (is (eq other btr:*current-bullet-world*)))
    (is (eq w btr:*current-bullet-world*))
    (signals btr:btr-error (btr:with-current-bullet-world 42 t))
    (is (eq w (var-value 'btr:?w (first (btr:prolog-?w '(btr:object btr:?w cup))))))
    (is (eq w (var-value '?w (first (btr:prolog-?w '(btr:object ?w tray))))) "?W of any package")
    (is (null (btr:prolog-?w '(btr:object ?w no-such-object))))
    (let ((fresh (var-value '?new (first (prolog '(btr:clear-bullet-world ?new))))))
      (is (typep fresh 'btr:bt-reasoning-world))
      (is (null (btr:object-names fresh)))
      (is (eq w btr:*current-bullet-world*)))
    (force-ll (prolog '(btr:clear-bullet-world)))
    (is (not (eq w btr:*current-bullet-world*)))
    (is (null (btr:object-names btr:*current-bullet-world*)))))

(test obj-pose-on-puts-the-bottom-on-the-pose
  (let* ((w (small-world)) (cup (btr:object w 'cup))
         (target (cl-transforms:make-pose (cl-transforms:make-3d-vector 0.3 0.1 0.7)
                                          (cl-transforms:make-identity-rotation)))
         (pose (btr:obj-pose-on target cup)))
    (setf (btr:pose cup) pose)
    (multiple-value-bind (lo hi) (btr:aabb cup)
      (is (< (abs (- 0.7 (cl-transforms:z lo))) 1d-6))
      (is (< (abs (- 0.3 (/ (+ (cl-transforms:x lo) (cl-transforms:x hi)) 2))) 1d-6)))
    (signals btr:btr-error (btr:obj-pose-on target 'cup))))

(test bounding-boxes-of-objects
  (let* ((w (small-world)) (cup (btr:object w 'cup)) (tray (btr:object w 'tray)))
    (let ((d (cl-bullet:bounding-box-dimensions cup))
          (c (cl-bullet:bounding-box-center cup)))
      (is (< (abs (- 0.1 (cl-transforms:z d))) 1d-3))
      (is (< (abs (- 0.79 (cl-transforms:z c))) 1d-3)))
    (is (cl-transforms:v= (btr:calculate-bb-dims cup) (cl-bullet:bounding-box-dimensions cup)))
    (let ((merged (btr:merge-bounding-boxes cup tray)))
      (is (cl-bullet:bounding-box-p merged))
      (is (< (abs (- 0.3 (cl-transforms:x (cl-bullet:bounding-box-dimensions merged)))) 1d-3))
      (is (< (abs (- 0.14 (cl-transforms:z (cl-bullet:bounding-box-dimensions merged)))) 2d-3)))
    (signals error (cl-bullet:bounding-box-center 42))))

(test local-aabb-is-the-box-in-the-objects-own-frame
  (let* ((w (small-world)) (tray (btr:object w 'tray)))
    (declare (ignorable w))
    (btr:add-object w :box 'plank '((1 2 0.5) (0 0 0 1)) :size '(0.4 0.1 0.02))
    (let ((plank (btr:object w 'plank)))
      (flet ((sizes (lo hi) (mapcar (lambda (f) (- (funcall f hi) (funcall f lo)))
                                    (list #'cl-transforms:x #'cl-transforms:y #'cl-transforms:z))))
        ;; turned 45 degrees about z and tipped 90 degrees about x: the map box changes, the
        ;; local one does not, and it is centred on the object's origin
        (setf (btr:pose plank)
              (cl-transforms:make-pose
               (cl-transforms:make-3d-vector -1 0.5 1.2)
               (cl-transforms:q* (cl-transforms:axis-angle->quaternion
                                  (cl-transforms:make-3d-vector 0 0 1) (/ pi 4))
                                 (cl-transforms:axis-angle->quaternion
                                  (cl-transforms:make-3d-vector 1 0 0) (/ pi 2)))))
        (multiple-value-bind (lo hi) (btr:local-aabb plank)
          (destructuring-bind (sx sy sz) (sizes lo hi)
            (is (< (abs (- sx 0.4)) 0.01) "x size ~a" sx)
            (is (< (abs (- sy 0.1)) 0.01) "y size ~a" sy)
            (is (< (abs (- sz 0.02)) 0.01) "z size ~a" sz))
          (is (< (abs (+ (cl-transforms:x lo) (cl-transforms:x hi))) 1d-6)))
        (multiple-value-bind (lo hi) (btr:aabb plank)
          (is (> (third (sizes lo hi)) 0.09) "the map box stands up: ~a" (sizes lo hi))))
      (signals error (btr:local-aabb 'plank))
      (btr:remove-object w 'plank)
      (signals error (btr:local-aabb plank))
      (is (< (abs (- 0.04 (let ((lo-hi (multiple-value-list (btr:local-aabb tray))))
                            (- (cl-transforms:z (second lo-hi)) (cl-transforms:z (first lo-hi))))))
             0.01)))))

(test link-aabbs-are-the-links-boxes
  (let ((w (small-world)))
    (btr:add-object w :urdf :lifter '((2 0 0) (0 0 0 1)) :urdf *arm-urdf*)
    (let* ((lifter (btr:object w :lifter))
           (boxes (btr:link-aabbs lifter)))
      (btr:set-robot-state-from-joints '(("lift" 0.2)) lifter)
      (is (not (equalp boxes (btr:link-aabbs lifter))) "the hand's box moved with it")
      (setf boxes (btr:link-aabbs lifter))
      (is (= 12 (length boxes)))
      (dotimes (i 2)
        (multiple-value-bind (lo hi) (btr:aabb lifter i)
          (is (equalp (vector (cl-transforms:x lo) (cl-transforms:y lo) (cl-transforms:z lo)
                              (cl-transforms:x hi) (cl-transforms:y hi) (cl-transforms:z hi))
                      (subseq boxes (* 6 i) (* 6 (1+ i)))))))
      (signals btr:btr-error (btr:link-aabbs (btr:object w 'cup)))
      (btr:remove-object w :lifter)
      (signals error (btr:link-aabbs lifter)))))

(test an-indexed-joint-is-set-as-by-name
  (let ((w (small-world)))
    (btr:add-object w :urdf :lifter '((2 0 0) (0 0 0 1)) :urdf *arm-urdf*)
    (let* ((lifter (btr:object w :lifter))
           (index (btr::joint-index lifter "lift")))
      (btr::set-indexed-joint lifter index 0.2d0)
      (is (= 0.2d0 (btr:joint-state lifter "lift")))
      (is (< (abs (- 0.5d0 (cl-transforms:z (cl-transforms:origin (btr:link-pose lifter "hand"))))) 1d-9))
      ;; within a hair of the limit: clamped without a word, as by name
      (btr::set-indexed-joint lifter index (+ 0.5d0 1d-9))
      (is (= 0.5d0 (btr:joint-state lifter "lift")))
      ;; a value that is no number is named with the joint and the object
      (let ((e (handler-case (progn (btr::set-indexed-joint lifter index :up) nil)
                 (btr:btr-error (e) e))))
        (is (not (null e)))
        (is (search "lift" (princ-to-string e)))
        (is (search ":UP" (princ-to-string e))))
      (is (= 0.5d0 (btr:joint-state lifter "lift"))))))

(test robot-joint-values-are-the-joint-states-by-index
  (let ((w (small-world)))
    (btr:add-object w :urdf :lifter '((2 0 0) (0 0 0 1)) :urdf *arm-urdf*)
    (let ((lifter (btr:object w :lifter)))
      (btr:set-robot-state-from-joints '(("lift" 0.3d0)) lifter)
      (let ((values (btr:robot-joint-values lifter)))
        (is (= (length (btr:joint-names lifter)) (length values)))
        (dolist (joint (btr:joint-names lifter))
          (is (= (btr:joint-state lifter joint) (aref values (btr:joint-index lifter joint)))))
        (is (= 0.3d0 (aref values (btr:joint-index lifter "lift"))))
        ;; a fresh vector: setting a joint later does not change it
        (btr:set-robot-state-from-joints '(("lift" 0.1d0)) lifter)
        (is (= 0.3d0 (aref values (btr:joint-index lifter "lift"))))))))

(test bad-poses-are-named-after-the-object
  (let* ((w (small-world)) (cup (btr:object w 'cup)))
    (flet ((message (pose)
             (handler-case (progn (setf (btr:pose cup) pose) nil)
               (btr:btr-error (e) (princ-to-string e)))))
      (let ((m (message '((1 2) (0 0 0 1)))))
        (is (search "pose of " m) "~a" m)
        (is (search (prin1-to-string 'cup) m) "~a" m))
      (let ((m (message (cl-transforms:make-pose (cl-transforms:make-3d-vector 1d9 0 0)
                                                 (cl-transforms:make-identity-rotation)))))
        (is (search (format nil "pose of ~s" 'cup) m) "~a" m)
        (is (search "BTR::*MAX-COORDINATE*" m) "~a" m)))
    (is (equal "pose of CRAM-BULLET-REASONING::X"
               (let ((*package* (find-package :cl-user)))
                 (princ-to-string (btr::pose-of 'btr::x)))))))

(test single-floats-become-their-printed-doubles
  (is (eql 0.3d0 (btr::to-double 0.3)))
  (is (eql 0.3d0 (btr::to-double 0.3)) "again, from the kept answer")
  (is (eql -1.25d0 (btr::to-double -1.25)))
  (is (eql 0.5d0 (btr::to-double 1/2)))
  (is (eql 2d0 (btr::to-double 2)))
  (is (eql 0.1d0 (btr::to-double 0.1f0))))

(test robot-attached-objects-in-collision
  (let* ((w (small-world))
         (arm (btr:add-object w :urdf 'arm '((2 0 0.05) (0 0 0 1)) :urdf *arm-urdf*))
         (cup (btr:object w 'cup)))
    (setf (btr:pose cup) (cl-transforms:make-pose (cl-transforms:make-3d-vector 2 0 0.35)
                                                  (cl-transforms:make-identity-rotation)))
    (btr:attach-object arm cup :link "hand")
    (is-false (btr:robot-attached-objects-in-collision w arm))
    (btr:add-object w :box 'wall '((2 0 0.39) (0 0 0 1)) :size '(0.02 0.5 0.02))
    (is-true (btr:robot-attached-objects-in-collision w arm))
    (signals btr:btr-error (btr:robot-attached-objects-in-collision w cup))))

(test timelines-record-world-states
  (let* ((w (small-world)) (cup (btr:object w 'cup))
         (timeline (btr:timeline-init w 0)))
    (setf (btr:pose cup) (cl-transforms:make-pose (cl-transforms:make-3d-vector 0.4 0 0.79)
                                                  (cl-transforms:make-identity-rotation)))
    (btr:timeline-advance timeline (btr:make-event w '(moved cup) 10))
    (btr:timeline-advance timeline (btr:make-event w '(looked) 5))
    (is (equal '(btr::start (looked) (moved cup))
               (mapcar #'btr:event (btr:timeline-events timeline))) "ordered by time")
    (flet ((cup-x-at (time)
             (second (find 'cup (btr:timeline-lookup timeline time) :key #'first))))
      (is (< (abs (cl-transforms:x (cl-transforms:origin (cup-x-at 3)))) 1d-6))
      (is (< (abs (- 0.4 (cl-transforms:x (cl-transforms:origin (cup-x-at 12))))) 1d-6)))
    (btr:with-timeline timeline
      (is (equal '(0 5 10) (mapcar (lambda (b) (var-value '?t b))
                                   (force-ll (prolog '(btr:occurs-in ?tl ?e ?t))))))
      (is-true (prolog '(btr:holds-at ?tl (btr:contact ?w cup tray) 0)))
      (is-false (prolog '(btr:holds-at ?tl (btr:contact ?w cup tray) 12)) "moved off the tray")
      ;; the event at 5 was made after the move, so it holds the moved cup
      (is (equal '(0) (mapcar (lambda (b) (var-value '?t b))
                              (force-ll (prolog '(btr:holds-at ?tl (btr:contact ?w cup tray) ?t)))))))
    (is (< (abs (- 0.4 (x-of cup))) 1d-6) "asking the past leaves the world as it is")
    (signals btr:btr-error (btr:timeline-advance timeline 'not-an-event))
    (signals btr:btr-error (btr:make-event w '(x) "noon"))))

(test generate-urdf-string-round-trips
  (let* ((robot (cl-urdf:parse-urdf *arm-urdf*))
         (text (cl-urdf:generate-urdf-string robot))
         (again (cl-urdf:parse-urdf text)))
    (is (equal "arm" (cl-urdf:name again)))
    (is (equal (cl-urdf:robot-link-names robot) (cl-urdf:robot-link-names again)))
    (is (equal (cl-urdf:robot-joint-names robot) (cl-urdf:robot-joint-names again)))
    (let ((j1 (gethash "lift" (cl-urdf:joints robot))) (j2 (gethash "lift" (cl-urdf:joints again))))
      (is (eq :prismatic (cl-urdf:joint-type j2)))
      (is (equal (cl-urdf:limits j1) (cl-urdf:limits j2)))
      (is (every (lambda (a b) (< (abs (- a b)) 1d-12))
                 (first (cl-urdf:origin j1)) (first (cl-urdf:origin j2))))
      (is (equal "base" (cl-urdf:name (cl-urdf:parent j2)))))
    (is (equal (cl-urdf:collision (gethash "hand" (cl-urdf:links robot)))
               (cl-urdf:collision (gethash "hand" (cl-urdf:links again)))))
    (signals cl-urdf:urdf-error (cl-urdf:generate-urdf-string "not a robot"))))

(test generate-urdf-string-of-the-pr2
  (let* ((path (asdf:system-relative-pathname "cram-plans/cram-pr2-description" "robots/pr2/pr2.urdf"))
         (robot (cl-urdf:parse-urdf path))
         (again (cl-urdf:parse-urdf (cl-urdf:generate-urdf-string robot))))
    (is (= (hash-table-count (cl-urdf:links robot)) (hash-table-count (cl-urdf:links again))))
    (is (= (hash-table-count (cl-urdf:joints robot)) (hash-table-count (cl-urdf:joints again))))
    (is (equal (cl-urdf:name (cl-urdf:root-link robot)) (cl-urdf:name (cl-urdf:root-link again))))))

(test call-without-collisions-keeps-an-object-out-of-the-physics
  ;; a static block stuck into the side of the cup: simulated normally it pushes the cup away;
  ;; with the block out of the physics the cup stays where it is, and afterwards the block
  ;; collides again
  (flet ((world-with-pusher ()
           (let ((w (small-world)))
             (btr:add-object w :box 'pusher '((0.05 0 0.79) (0 0 0 1)) :size '(0.06 0.06 0.1))
             w)))
    (let* ((w (world-with-pusher)) (cup (btr:object w 'cup)) (x0 (x-of cup)))
      (btr:simulate w 0.5)
      (is (> (abs (- (x-of cup) x0)) 0.005d0)))
    (let* ((w (world-with-pusher)) (cup (btr:object w 'cup)) (pusher (btr:object w 'pusher))
           (x0 (x-of cup)))
      (multiple-value-bind (group mask) (cram-native:object-collision-filter (btr:world-handle w)
                                                                        (btr:object-handle pusher))
        (is (eq :done (btr:call-without-collisions
                       pusher (lambda ()
                                (btr:simulate w 0.5)
                                (is (not (btr:objects-in-contact-p w cup pusher)))
                                :done))))
        (is (< (abs (- (x-of cup) x0)) 0.001d0))
        (is (equal (list group mask)
                   (multiple-value-list (cram-native:object-collision-filter
                                         (btr:world-handle w) (btr:object-handle pusher)))))
        (is (btr:objects-in-contact-p w cup pusher)))))
  (signals btr:btr-error (btr:call-without-collisions 'no-such-object (lambda () t))))

(test mesh-uris-resolve-to-the-file-as-it-is-now
  "RESOLVE-URI gives the truename of the file a URI names, also when asked again, and follows a
changed file: a file gone signals an error naming it, a symbolic link pointed elsewhere gives
the new target."
  (let* ((dir (uiop:ensure-directory-pathname
               (format nil "/tmp/cram-plans-uri-test-~d/" (sb-posix:getpid))))
         (a (merge-pathnames "a.stl" dir))
         (b (merge-pathnames "b.stl" dir))
         (link (merge-pathnames "mesh.stl" dir)))
    (ensure-directories-exist dir)
    (unwind-protect
         (progn
           (dolist (f (list a b))
             (with-open-file (s f :direction :output :if-exists :supersede) (write-line "solid x" s)))
           (sb-posix:symlink (namestring a) (namestring link))
           (is (equal (truename a) (btr::resolve-uri (namestring link))))
           (is (equal (truename a) (btr::resolve-uri (namestring link))))
           (delete-file link)
           (sb-posix:symlink (namestring b) (namestring link))
           (is (equal (truename b) (btr::resolve-uri (namestring link))))
           (delete-file link)
           (let ((c (handler-case (progn (btr::resolve-uri (namestring link)) nil) (error (e) e))))
             (is (typep c 'error))
             (is (search "mesh.stl" (princ-to-string c)))))
      (uiop:delete-directory-tree dir :validate t :if-does-not-exist :ignore))))
