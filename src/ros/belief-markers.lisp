;;;; The belief state's items as rviz markers: meshes as package:// (or file://) mesh resources,
;;;; primitives as boxes, spheres and cylinders, in the objects' colours.

(in-package :roslisp-utilities)

(defvar *marker-namespace* "belief_state"
  "The marker namespace (ns) of the belief state's object markers.")

(defvar *marker-ids* (make-hash-table :test 'eq)
  "Object name → marker id; an object keeps its id for the life of the image.")

(defvar *marker-ids-lock* (bt:make-lock "marker ids"))

(defun marker-id (name)
  "The marker id of the object NAME (assigned on first use, counting from 1)."
  (bt:with-lock-held (*marker-ids-lock*)
    (or (gethash name *marker-ids*)
        (setf (gethash name *marker-ids*) (1+ (hash-table-count *marker-ids*))))))

(defvar *marker-mesh-uris* :file
  "How mesh markers name their files. :FILE (the default): file:// URIs of the resolved files,
which an rviz on this machine loads whatever its ROS_PACKAGE_PATH. :PACKAGE: package:// URIs as
the objects were made with, for an rviz on another machine whose ROS_PACKAGE_PATH holds the
packages (resources/ is the package cram_plans_resources).")

(defun mesh-resource-uri (mesh)
  "A URI rviz can load for MESH (a keyword of BTR:*MESH-FILES*, a URI string or a path), or NIL
when MESH names no known file. package:// URIs become file:// URIs unless *MARKER-MESH-URIS*
is :PACKAGE."
  (unless (member *marker-mesh-uris* '(:file :package))
    (ros-fail "*MARKER-MESH-URIS* is ~s, expected :FILE or :PACKAGE" *marker-mesh-uris*))
  (flet ((file-uri (path)
           (let ((true (ignore-errors (probe-file path))))
             (and true (concatenate 'string "file://" (namestring true))))))
    (etypecase mesh
      (keyword (let ((uri (second (assoc mesh btr:*mesh-files*))))
                 (and uri (mesh-resource-uri uri))))
      (string (cond ((uiop:string-prefix-p "file://" mesh) mesh)
                    ((uiop:string-prefix-p "package://" mesh)
                     (if (eq *marker-mesh-uris* :package)
                         mesh
                         (let ((path (ignore-errors (btr::resolve-uri mesh))))
                           (if path (file-uri path) mesh))))
                    (t (file-uri mesh))))
      (pathname (file-uri mesh))
      (null nil))))

(defun object-spec (object)
  "The ADD-OBJECT type and keys OBJECT was made with, as (values kind plist)."
  (values (btr:object-kind object)
          (btr:object-spec object)))

(defun scale-list (scale)
  "A mesh SCALE (a real or (sx sy sz)) as a list of three doubles."
  (mapcar (lambda (s) (coerce s 'double-float))
          (if (listp scale) scale (list scale scale scale))))

(defun bounding-box-list (object)
  (let ((v (btr:bounding-box object)))
    (mapcar (lambda (s) (max 1d-3 (coerce s 'double-float)))
            (list (cl-transforms:x v) (cl-transforms:y v) (cl-transforms:z v)))))

(defun object-color-list (object)
  "OBJECT's colour as (r g b a) single floats; a missing or zero alpha becomes 1."
  (let* ((c (mapcar (lambda (x) (coerce x 'single-float)) (btr:object-color object)))
         (rgb (subseq (append c (list 0.5 0.5 0.5)) 0 3))
         (a (fourth c)))
    (append rgb (list (if (and a (> a 0)) a 1.0)))))

(defun object-marker (object)
  "The marker of the item OBJECT as a plist (:name :id :type :pose :scale :color :mesh-resource).
:TYPE is :MESH_RESOURCE for meshes with a loadable file, :CUBE, :SPHERE or :CYLINDER for the
primitives, and :CUBE of the bounding box size for anything else."
  (multiple-value-bind (kind spec) (object-spec object)
    (let* ((mesh (and (eq kind :mesh) (mesh-resource-uri (getf spec :mesh))))
           (size (getf spec :size))
           (type-and-scale
             (cond (mesh (list :mesh_resource (scale-list (getf spec :scale 1))))
                   ((and (member kind '(:box :colored-box)) size) (list :cube (scale-list size)))
                   ((and (eq kind :sphere) (realp (getf spec :radius 0.05)))
                    (let ((d (* 2 (getf spec :radius 0.05)))) (list :sphere (scale-list d))))
                   ((and (eq kind :cylinder) size) (list :cylinder (scale-list size)))
                   (t (list :cube (bounding-box-list object))))))
      (list :name (btr:name object)
            :id (marker-id (btr:name object))
            :type (first type-and-scale)
            :pose (btr:pose object)
            :scale (second type-and-scale)
            :color (object-color-list object)
            :mesh-resource (or mesh "")))))

(defun belief-state-markers (&key (world btr:*current-bullet-world*))
  "Marker descriptions (plists, see OBJECT-MARKER) of every item of WORLD, oldest first. Robots,
environments and the floor are drawn by rviz's RobotModel displays and get no marker."
  (check-world world)
  (call-with-world-lock
   world
   (lambda ()
     (loop for o in (btr:objects world)
           when (typep o 'btr:item) collect (object-marker o)))))
