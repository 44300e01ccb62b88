;;;; Headless pictures (OSMesa through the shim) and visibility from a robot's camera.

(in-package :cram-bullet-reasoning)

;;; ---- snapshots ---------------------------------------------------------------------------------

(defvar *snapshot-directory* nil
  "Directory where DEBUG-WINDOW and SNAPSHOT write PNG pictures in headless runs; NIL: none.")

(defvar *debug-snapshots* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "The worlds with an open (headless) debug window, as the keys of a weak hash table: SNAPSHOT
records pictures of them. A world no one else holds leaves it (it is collected as usual), and
a world whose native world was destroyed is dropped from it, so replacing the belief state
run after run keeps nothing.")

(defvar *snapshot-counter* 0 "Number of the next snapshot file.")

(defvar *camera-pose* nil
  "Default camera pose for pictures (a pose, optical convention) or NIL to frame the scene.")

(defun scene-center (world)
  "Centre of the robot if there is one, else of the bounding boxes of the items."
  (let ((robot (ignore-errors (get-robot-object world))))
    (if robot
        (cl-transforms:origin (pose robot))
        (let ((items (remove-if-not (lambda (o) (typep o 'item)) (objects world))))
          (if items
              (cl-transforms:v* (reduce #'cl-transforms:v+ (mapcar (lambda (o) (cl-transforms:origin (pose o))) items))
                                (/ 1d0 (length items)))
              (cl-transforms:make-3d-vector 0 0 0))))))

(defun default-camera (world &key (distance 4.5d0))
  "A camera pose looking down at the scene centre from the front left, 45 degrees elevated."
  (let* ((c (scene-center world))
         (target (list (cl-transforms:x c) (cl-transforms:y c) (+ 0.6d0 (cl-transforms:z c))))
         (eye (list (- (first target) (* distance 0.75)) (- (second target) (* distance 0.45))
                    (+ (third target) (* distance 0.6)))))
    (vector->pose (native:look-at eye target))))

(defun camera-vector (world camera-pose)
  (if camera-pose (pose->vector camera-pose "camera pose")
      (pose->vector (or *camera-pose* (default-camera world)))))

(defun png-snapshot (path &key (world *current-bullet-world*) camera-pose (width 640) (height 480)
                              (fov 50) look-at)
  "Render WORLD headless into the PNG file PATH from CAMERA-POSE (optical convention), or from
a camera looking at LOOK-AT (x y z) from the default direction, or from a default view. Returns PATH."
  (ensure-directories-exist path)
  (let ((cam (if look-at
                 (let ((d 3.5d0) (tx (first look-at)) (ty (second look-at)) (tz (third look-at)))
                   (native:look-at (list (- tx (* d 0.7)) (- ty (* d 0.5)) (+ tz (* d 0.55))) look-at))
                 (camera-vector world camera-pose))))
    (native:render-png (world-handle world) cam (namestring path) :width width :height height :fov fov)
    path))

(defun render-camera-image (camera-pose &key (world *current-bullet-world*) (width 320) (height 240)
                                             (fov 50) depth segmentation)
  "Render WORLD from CAMERA-POSE (optical convention) and return the RGB bytes, and when asked
the depth and segmentation buffers (see CRAM-NATIVE:RENDER)."
  (native:render (world-handle world) (pose->vector camera-pose "camera pose")
                 :width width :height height :fov fov :depth depth :segmentation segmentation))

(defvar *debug-window-hook* nil
  "NIL or a function of the world that DEBUG-WINDOW calls: the browser viewer (cram-plans/viewer)
is started from here, as the window when there is no display.")

(defun debug-window (&optional (world *current-bullet-world*))
  "Headless stand-in for CRAM's debug window: from now on SNAPSHOT records pictures of WORLD
into *SNAPSHOT-DIRECTORY* (when set); a first picture is written at once. *DEBUG-WINDOW-HOOK*
then starts the browser viewer on WORLD and prints its URL."
  (unless (typep world 'bt-world)
    (btr-fail "DEBUG-WINDOW: ~s is not a Bullet world" world))
  (forget-destroyed-debug-windows)
  (setf (gethash world *debug-snapshots*) t)
  (snapshot "debug-window" world)
  (when *debug-window-hook* (funcall *debug-window-hook* world))
  world)

(defun %world-live-p (world)
  "True when the native world of WORLD has not been destroyed."
  (native:world-alive-p (world-handle world)))

(defun forget-destroyed-debug-windows ()
  "Drop the worlds whose native world is gone from *DEBUG-SNAPSHOTS*."
  (let ((dead '()))
    (maphash (lambda (w v) (declare (ignore v)) (unless (%world-live-p w) (push w dead)))
             *debug-snapshots*)
    (dolist (w dead) (remhash w *debug-snapshots*))))

(defun snapshot (label &optional (world *current-bullet-world*))
  "Write a picture of WORLD named NNN-LABEL.png to *SNAPSHOT-DIRECTORY* when WORLD has a debug
window and the directory is set. Returns the path or NIL."
  (when (and *snapshot-directory* (gethash world *debug-snapshots*) (%world-live-p world))
    (let ((path (merge-pathnames (format nil "~3,'0d-~a.png" (incf *snapshot-counter*)
                                         (substitute-if #\- (lambda (c) (not (or (alphanumericp c) (char= c #\-)))) (string-downcase label)))
                                 (uiop:ensure-directory-pathname *snapshot-directory*))))
      (png-snapshot path :world world))))

;;; ---- visibility -----------------------------------------------------------------------------------

(defparameter *visibility-threshold* 0.9
  "Share of an object's pixels that must be unoccluded for it to count as visible.")

(defun camera-pose (robot-name &optional (world *current-bullet-world*))
  "The world pose of the first camera frame of the robot ROBOT-NAME (rob-int facts)."
  (let* ((robot (object-or-fail world robot-name))
         (frames (mapcar (lambda (b) (var-value '?frame b))
                         (force-ll (prolog `(rob-int:camera-frame ,robot-name ?frame)))))
         (frame (find-if (lambda (f) (link-exists-p robot f)) frames)))
    (unless frame
      (btr-fail "robot ~s has no camera frame among ~s (rob-int:camera-frame facts)" robot-name frames))
    (link-pose robot frame)))

(defun sunk-below-z (world object)
  "The height up to which the item OBJECT is sunk into what it stands on, or NIL: the highest
top of a part of another object (a link of an articulated one; not the robot's) whose bounding
box holds OBJECT's centre in x and y and whose top lies between OBJECT's bottom and its centre.
An item spawned a little into a shelf board keeps that part hidden from every camera; it is not
part of what can be seen."
  (when (typep object 'item)
    (multiple-value-bind (lo hi) (aabb object)
      (let ((bottom (cl-transforms:z lo))
            (centre (/ (+ (cl-transforms:z lo) (cl-transforms:z hi)) 2))
            (x (/ (+ (cl-transforms:x lo) (cl-transforms:x hi)) 2))
            (y (/ (+ (cl-transforms:y lo) (cl-transforms:y hi)) 2))
            (robot (ignore-errors (get-robot-object world)))
            (best nil))
        (flet ((consider (x0 y0 x1 y1 top)
                 (when (and (> top bottom) (< top centre)
                            (<= x0 x x1) (<= y0 y y1)
                            (or (null best) (> top best)))
                   (setf best top))))
          (dolist (other (objects world))
            (unless (or (eq other object) (eq other robot))
              (if (typep other 'robot-object)
                  (let ((boxes (link-aabbs other)))
                    (dotimes (i (length (link-names other)))
                      (let ((k (* 6 i)))
                        (consider (aref boxes k) (aref boxes (+ k 1))
                                  (aref boxes (+ k 3)) (aref boxes (+ k 4)) (aref boxes (+ k 5))))))
                  (multiple-value-bind (slo shi) (aabb other)
                    (consider (cl-transforms:x slo) (cl-transforms:y slo)
                              (cl-transforms:x shi) (cl-transforms:y shi) (cl-transforms:z shi)))))))
        best))))

(defun visibility-fraction (camera-pose object &key (world *current-bullet-world*))
  "The unoccluded share of OBJECT (object or name) seen from CAMERA-POSE (optical convention),
and the names of the occluding objects. The part of an item sunk into the board it stands on
(SUNK-BELOW-Z) counts neither as seen nor as hidden."
  (let* ((o (ensure-object world object))
         (min-z (sunk-below-z world o)))
    (multiple-value-bind (fraction occluders)
        (native:visibility (world-handle world) (pose->vector camera-pose "camera pose")
                           (object-handle o) :min-z min-z)
      (values fraction
              (loop for h in occluders for oc = (object-by-handle world h) when oc collect (name oc))))))

(defun object-visible-p (world camera-pose object)
  "True when at least *VISIBILITY-THRESHOLD* of OBJECT is unoccluded from CAMERA-POSE."
  (>= (visibility-fraction camera-pose object :world world) *visibility-threshold*))

(defun occluding-objects (world camera-pose object)
  "Names of the objects hiding parts of OBJECT from CAMERA-POSE."
  (nth-value 1 (visibility-fraction camera-pose object :world world)))
