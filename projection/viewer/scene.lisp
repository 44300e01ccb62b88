;;;; Scene descriptions of a belief state for the browser: every object's shapes as the shim
;;;; draws them (URDF visuals with their colours, collision geometry for links without visuals,
;;;; primitive and mesh bodies), articulated objects' kinematic trees for forward kinematics in
;;;; the page, and compact states (base poses and joint values) — plus a small JSON writer.

(in-package :cram-viewer)

;;; ---- JSON ----------------------------------------------------------------------------------

(defun write-json-number (x stream)
  (cond ((integerp x) (format stream "~d" x))
        ((not (< (abs x) most-positive-double-float))
         (error "JSON: the number ~s is not finite" x))
        (t (let* ((r (round (* x 100000)))
                  (s (format nil "~d" (abs r)))
                  (s (if (< (length s) 6) (concatenate 'string (make-string (- 6 (length s)) :initial-element #\0) s) s))
                  (int (subseq s 0 (- (length s) 5)))
                  (frac (string-right-trim "0" (subseq s (- (length s) 5)))))
             (when (minusp r) (write-char #\- stream))
             (write-string int stream)
             (when (plusp (length frac)) (write-char #\. stream) (write-string frac stream))))))

(defun write-json-string (s stream)
  (write-char #\" stream)
  (loop for c across s
        do (case c
             (#\" (write-string "\\\"" stream))
             (#\\ (write-string "\\\\" stream))
             (#\Newline (write-string "\\n" stream))
             (#\Return (write-string "\\r" stream))
             (#\Tab (write-string "\\t" stream))
             (t (if (< (char-code c) 32)
                    (format stream "\\u~4,'0x" (char-code c))
                    (write-char c stream)))))
  (write-char #\" stream))

(defun write-json (value &optional (stream *standard-output*))
  "Write VALUE as JSON: hash tables (string keys) as objects, lists and non-string vectors as
arrays, strings, reals (5 decimals), :TRUE, :FALSE, :NULL, and T / NIL as true / null.
Anything else is an error naming it."
  (typecase value
    (hash-table
     (write-char #\{ stream)
     (let ((first t))
       (maphash (lambda (k v)
                  (unless first (write-char #\, stream))
                  (setf first nil)
                  (write-json-string (if (stringp k) k (string-downcase (string k))) stream)
                  (write-char #\: stream)
                  (write-json v stream))
                value))
     (write-char #\} stream))
    (string (write-json-string value stream))
    ((member t :true) (write-string "true" stream))
    ((member :false) (write-string "false" stream))
    ((member nil :null) (write-string "null" stream))
    (real (write-json-number value stream))
    ((or list vector)
     (write-char #\[ stream)
     (let ((first t))
       (map nil (lambda (v)
                  (unless first (write-char #\, stream))
                  (setf first nil)
                  (write-json v stream))
            value))
     (write-char #\] stream))
    (symbol (write-json-string (string-downcase (symbol-name value)) stream))
    (t (error "JSON: cannot encode ~s (a ~s)" value (type-of value)))))

(defun json-string (value)
  "VALUE as a JSON string (see WRITE-JSON)."
  (with-output-to-string (s) (write-json value s)))

(defun obj (&rest keys-and-values)
  "A JSON object (an EQUAL hash table) from alternating string keys and values."
  (let ((h (make-hash-table :test 'equal)))
    (loop for (k v) on keys-and-values by #'cddr do (setf (gethash k h) v))
    h))

;;; ---- meshes --------------------------------------------------------------------------------

(defvar *meshes* (make-hash-table :test 'equal :synchronized t)
  "Resolved mesh file name → its id (\"m0\", \"m1\" ...), for the page to load once.")

(defvar *mesh-paths* (make-hash-table :test 'equal :synchronized t)
  "Mesh id → resolved file name.")

(defun mesh-id (path)
  "The id of the mesh file PATH (registered on first use)."
  (let ((file (namestring (or (btr::probe-file-again path)
                              (error "viewer: mesh file ~a does not exist" path)))))
    (or (gethash file *meshes*)
        (sb-ext:with-locked-hash-table (*meshes*)
          (or (gethash file *meshes*)
              (let ((id (format nil "m~d" (hash-table-count *meshes*))))
                (setf (gethash id *mesh-paths*) file
                      (gethash file *meshes*) id)))))))

(defun mesh-file (id)
  "The file of the mesh ID, or NIL."
  (values (gethash id *mesh-paths*)))

(defun mesh-format (file)
  (let ((type (string-downcase (or (pathname-type file) ""))))
    (cond ((member type '("stl" "obj" "dae") :test #'string=) type)
          (t (error "viewer: mesh ~a has type ~s, expected stl, obj or dae" file type)))))

(defun mesh-table (ids &key embed)
  "JSON object: mesh id → {format, url} (served by the viewer) or, with EMBED, {format, data}
with the file's bytes in base64 (a replay that opens from disk)."
  (let ((h (make-hash-table :test 'equal)))
    (dolist (id ids h)
      (let ((file (or (mesh-file id) (error "viewer: unknown mesh id ~s" id))))
        (setf (gethash id h)
              (if embed
                  (obj "format" (mesh-format file)
                       "data" (cl-base64:usb8-array-to-base64-string
                               (alexandria:read-file-into-byte-vector file)))
                  (obj "format" (mesh-format file) "url" (format nil "mesh/~a" id))))))))

;;; ---- geometry --------------------------------------------------------------------------------

(defun pose7 (v &optional (offset 0))
  "The 7 numbers of the pose stored in the double vector V at OFFSET, as a list."
  (loop for i from offset below (+ offset 7) collect (aref v i)))

(defun origin7 (origin)
  "A URDF origin ((x y z) (qx qy qz qw)) as a list of 7 numbers."
  (append (first origin) (second origin)))

(defun urdf-geometry (geometry)
  "A JSON geometry of the CL-URDF geometry plist GEOMETRY (box, cylinder, sphere, mesh)."
  (ecase (first geometry)
    (:box (obj "type" "box" "size" (getf (rest geometry) :size)))
    (:cylinder (obj "type" "cylinder" "radius" (getf (rest geometry) :radius)
                    "length" (getf (rest geometry) :length)))
    (:sphere (obj "type" "sphere" "radius" (getf (rest geometry) :radius)))
    (:mesh (obj "type" "mesh"
                "mesh" (mesh-id (btr::resolve-uri (getf (rest geometry) :filename)))
                "scale" (getf (rest geometry) :scale)))))

(defun body-geometry (object)
  "The JSON geometry of the plain body OBJECT, as the shim holds it (BODY-SHAPE)."
  (multiple-value-bind (kind dims)
      (native:body-shape (btr::whandle object) (btr:object-handle object))
    (ecase kind
      (:plane (obj "type" "plane" "normal" (subseq dims 0 3) "constant" (fourth dims)))
      (:box (obj "type" "box" "size" dims))
      (:sphere (obj "type" "sphere" "radius" (first dims)))
      (:cylinder (obj "type" "cylinder" "radius" (first dims) "length" (second dims)))
      (:cone (obj "type" "cone" "radius" (first dims) "length" (second dims)))
      (:mesh (obj "type" "mesh"
                  "mesh" (mesh-id (btr::mesh-path (getf (btr:object-spec object) :mesh)))
                  "scale" dims))
      (:hull (obj "type" "hull"
                  "points" (mapcar (lambda (p) (mapcar (lambda (x) (coerce x 'double-float)) p))
                                   (getf (btr:object-spec object) :points)))))))

;;; ---- articulated objects ------------------------------------------------------------------------

(defvar *model-cache* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Parsed URDF (the same for the models of every belief state built from it) → the colourless
JSON description of its model.")

(defun link-visual-specs (link)
  "The (origin geometry colour) triples the shim draws for the CL-URDF LINK: its visuals, or
its collision geometry (colour NIL) when it has none."
  (or (mapcar (lambda (v) (list (getf v :origin) (getf v :geometry) (getf v :color)))
              (cl-urdf:visual link))
      (mapcar (lambda (c) (list (getf c :origin) (getf c :geometry) nil))
              (cl-urdf:collision link))))

(defun model-description (robot)
  "The colourless description of ROBOT's model: link names, joints (shim order, with origin,
axis, type, parent and child link indices) and the visuals of every link."
  (let ((model (btr::%model robot)))
    ;; keyed on the parsed URDF: a new belief state builds a new model of the same URDF
    (or (gethash (btr:urdf robot) *model-cache*)
        (setf (gethash (btr:urdf robot) *model-cache*)
              (let* ((urdf (btr:urdf robot))
                     (links (btr::km-link-names model))
                     (joints (loop for name across (btr::km-joint-names model)
                                   for info across (btr::km-joint-info model)
                                   for j = (gethash name (cl-urdf:joints urdf))
                                   collect (obj "name" name
                                                "type" (string-downcase (symbol-name (getf info :type)))
                                                "parent" (getf info :parent) "child" (getf info :child)
                                                "origin" (if j (origin7 (cl-urdf:origin j)) '(0 0 0 0 0 0 1))
                                                "axis" (getf info :axis))))
                     (visuals (loop for name across links for i from 0
                                    for link = (gethash name (cl-urdf:links urdf))
                                    when link
                                      append (loop for (origin geometry color) in (link-visual-specs link)
                                                   collect (list i (obj "link" i "origin" (origin7 origin)
                                                                        "geometry" (urdf-geometry geometry))
                                                                 color)))))
                (list :links (coerce links 'list) :joints joints
                      :root (position (cl-urdf:name (cl-urdf:root-link urdf)) links :test #'string=)
                      :visuals visuals))))))

(defun coloured-visuals (robot description)
  "The visuals of DESCRIPTION with the colours the shim draws for ROBOT: a link's own colour
(its first coloured visual, grey, or a colour set on the link) unless the visual has one of its
own and the link's colour was not overridden."
  (let ((link-colours (make-hash-table)))
    (loop for (i visual colour) in (getf description :visuals)
          for link-colour = (or (gethash i link-colours)
                                (setf (gethash i link-colours) (btr:object-color robot i)))
          for first-own = (third (find i (getf description :visuals) :key #'first))
          collect (let ((v (alexandria:copy-hash-table visual)))
                    (setf (gethash "color" v)
                          (if (and colour first-own
                                   (every (lambda (a b) (< (abs (- a b)) 1d-6)) first-own link-colour))
                              colour
                              link-colour))
                    v))))

(defparameter *camera-fov* 50
  "Vertical field of view (degrees) drawn for robot cameras: the one visibility renders with.")

(defun camera-description (robot)
  "{link, fov, aspect} of ROBOT's first camera frame that is one of its links (rob-int
CAMERA-FRAME facts), or NIL."
  (let* ((frames (ignore-errors
                  (mapcar (lambda (b) (cut:var-value '?frame b))
                          (cut:force-ll (prolog:prolog `(rob-int:camera-frame ,(btr:name robot) ?frame))))))
         (frame (find-if (lambda (f) (and (stringp f) (btr:link-exists-p robot f))) frames)))
    (and frame (obj "link" frame "fov" *camera-fov* "aspect" (/ 4d0 3)))))

(defvar *descriptor-cache* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Parsed URDF of an articulated object → (key . descriptor) of the last one described:
descriptors are not modified after they are made, so an object with the same name, types,
URDF, link colours and camera shares it.")

(defun link-colours (robot description)
  "The colour of every link of ROBOT that has a visual in DESCRIPTION, in order."
  (let* ((colours (btr:link-colors robot))
         (seen (make-array (length colours) :element-type 'bit :initial-element 0)))
    (loop for (i) in (getf description :visuals)
          when (zerop (sbit seen i))
            do (setf (sbit seen i) 1)
            and collect (svref colours i))))

(defun object-descriptor (object)
  "The JSON description of OBJECT (a BTR object) for the page: name, kind (body or
articulated), types, shapes with colours and, for articulated objects, links and joints."
  (let ((name (string-downcase (princ-to-string (btr:name object))))
        (types (mapcar (lambda (ty) (string-downcase (princ-to-string ty))) (btr:item-types object))))
    (if (typep object 'btr:robot-object)
        (let* ((d (model-description object))
               (camera (camera-description object))
               (key (list name types (link-colours object d) (and camera (gethash "link" camera))))
               (cache (gethash (btr:urdf object) *descriptor-cache*)))
          ;; a new belief state builds the same kitchen and robot again: describe them once
          (or (and cache (equal (car cache) key) (cdr cache))
              (let ((descriptor
                      (obj "name" name "kind" "articulated" "types" types
                           "urdf" (cl-urdf:name (btr:urdf object))
                           "links" (getf d :links) "joints" (getf d :joints) "root" (getf d :root)
                           "visuals" (coloured-visuals object d)
                           "camera" camera)))
                (setf (gethash (btr:urdf object) *descriptor-cache*) (cons key descriptor))
                descriptor)))
        (obj "name" name "kind" "body" "types" types
             "visuals" (list (obj "link" -1 "origin" '(0 0 0 0 0 0 1)
                                  "geometry" (body-geometry object)
                                  "color" (btr:object-color object)))))))

(defun descriptor-meshes (descriptors)
  "The mesh ids used by DESCRIPTORS."
  (let ((ids '()))
    (dolist (d descriptors (nreverse ids))
      (dolist (v (gethash "visuals" d))
        (let ((m (gethash "mesh" (gethash "geometry" v))))
          (when m (pushnew m ids :test #'string=)))))))

;;; ---- states --------------------------------------------------------------------------------------

(defun capture-state (world)
  "The state of WORLD: (values names vector) where NAMES is the object order list (shared while
the world's objects do not change) and VECTOR holds, per object, its pose (7 numbers) and for an
articulated object every joint value in shim order."
  (btr::with-world-lock (world)
    (let* ((names (btr::%object-order world))
           (objects (mapcar (lambda (n) (gethash n (btr::%objects world))) names))
           (w (btr:world-handle world))
           (handles (map '(simple-array (signed-byte 32) (*)) #'btr:object-handle objects))
           (poses (native:object-poses w handles))
           (joints (loop for o in objects
                         when (typep o 'btr:robot-object)
                           collect (native:robot-joints w (btr:object-handle o))))
           (n (+ (length poses) (reduce #'+ joints :key #'length)))
           (v (make-array n :element-type 'double-float))
           (k 0))
      (declare (type (simple-array double-float (*)) v poses))
      (loop for o in objects for i from 0
            do (replace v poses :start1 k :start2 (* 7 i) :end2 (* 7 (1+ i)))
               (incf k 7)
               (when (typep o 'btr:robot-object)
                 (let ((j (pop joints)))
                   (replace v j :start1 k)
                   (incf k (length j)))))
      (values names v))))

(defun split-state (names vector joint-counts)
  "A JSON object name → {pose, joints} of the state (NAMES VECTOR); JOINT-COUNTS maps a name to
its number of joints (0 for bodies)."
  (let ((h (make-hash-table :test 'equal)) (k 0))
    (dolist (n names h)
      (let* ((key (string-downcase (princ-to-string n)))
             (nj (gethash key joint-counts 0)))
        (when (> (+ k 7 nj) (length vector))
          (error "viewer: state of ~d numbers is too short for object ~s" (length vector) n))
        (setf (gethash key h)
              (obj "pose" (pose7 vector k)
                   "joints" (coerce (subseq vector (+ k 7) (+ k 7 nj)) 'list)))
        (incf k (+ 7 nj))))))

(defun world-scene (world &key embed-meshes)
  "The JSON description of WORLD: {objects: [descriptors], meshes: {...}}."
  (let ((descriptors (mapcar #'object-descriptor (btr:objects world))))
    (obj "objects" descriptors
         "meshes" (mesh-table (descriptor-meshes descriptors) :embed embed-meshes))))

(defun joint-counts (descriptors)
  (let ((h (make-hash-table :test 'equal)))
    (dolist (d descriptors h)
      (setf (gethash (gethash "name" d) h) (length (gethash "joints" d))))))

(defun world-state (world)
  "The current state of WORLD as JSON: object name → {pose, joints}."
  (multiple-value-bind (names v) (capture-state world)
    (let ((counts (make-hash-table :test 'equal)))
      (dolist (n names)
        (let ((o (btr:object world n)))
          (setf (gethash (string-downcase (princ-to-string n)) counts)
                (if (typep o 'btr:robot-object) (length (btr::km-joint-names (btr::%model o))) 0))))
      (split-state names v counts))))
