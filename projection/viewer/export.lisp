;;;; Runs as JSON (steps, task tree, overlays), the page's HTML, and replays written to a
;;;; directory that open from disk: replay.html (page, script, style and data inline),
;;;; replay.json, and the three.js files copied from Debian's libjs-three at run time.

(in-package :cram-viewer)

(defparameter *replay-three-directory* #p"/usr/share/javascript/three/"
  "Debian's libjs-three, where WRITE-REPLAY copies three.js from.")

(defparameter *replay-three-files*
  '(("three.min.js" . "build/three.min.js")
    ("OrbitControls.js" . "examples/js/controls/OrbitControls.js")
    ("STLLoader.js" . "examples/js/loaders/STLLoader.js")
    ("OBJLoader.js" . "examples/js/loaders/OBJLoader.js")
    ("ColladaLoader.js" . "examples/js/loaders/ColladaLoader.js")
    ("ConvexHull.js" . "examples/js/math/ConvexHull.js")
    ("ConvexGeometry.js" . "examples/js/geometries/ConvexGeometry.js"))
  "The three.js files a replay needs: name → path under *REPLAY-THREE-DIRECTORY*.")

;;; ---- overlays ---------------------------------------------------------------------------------

(defvar *heat-maps* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Costmap → its heat-map JSON (computed once).")

(defun heat-map-json (costmap)
  "The heat map of COSTMAP: {width, height, bounds [x0 y0 x1 y1], rgb (base64, rows from +y)}."
  (or (gethash costmap *heat-maps*)
      (setf (gethash costmap *heat-maps*)
            (multiple-value-bind (rgb w h x0 y0 x1 y1) (costmap:costmap-heat-map-image costmap)
              (obj "width" w "height" h "bounds" (list x0 y0 x1 y1)
                   "rgb" (cl-base64:usb8-array-to-base64-string rgb))))))

(defun overlay-json (overlay)
  "OVERLAY as sent to the page: a location overlay's costmap becomes a heat map, its samples
are listed oldest first and the last one validated is the chosen pose; a sweep overlay's sweep
becomes its JSON (SWEEP-OVERLAY)."
  (when (and (equal (gethash "type" overlay) "sweep") (gethash "sweep" overlay))
    (return-from overlay-json (sweep-overlay (gethash "sweep" overlay))))
  (if (equal (gethash "type" overlay) "location")
      (let ((samples (sb-thread:with-mutex (*recorder-lock*) (copy-list (gethash "samples" overlay))))
            (costmap (gethash "costmap" overlay)))
        (obj "type" "location" "designator" (overlay-designator-text (gethash "designator" overlay))
             "heat" (and costmap (heat-map-json costmap))
             "samples" (reverse samples) "chosen" (first samples)))
      overlay))

(defun overlays-json (overlays)
  "The JSON of the list OVERLAYS (see OVERLAY-JSON)."
  (mapcar #'overlay-json overlays))

;;; ---- runs --------------------------------------------------------------------------------------

(defun tree-json (root steps)
  "The task tree under ROOT as JSON, each node with an id, and first_step: the first of STEPS
recorded inside it (for a click on the node to jump to)."
  (let ((ids (make-hash-table :test 'eq)) (first-step (make-hash-table :test 'eq)) (n 0))
    (loop for s across steps
          do (loop for node = (step-node s) then (cpl:node-parent node) while node
                   do (unless (gethash node first-step) (setf (gethash node first-step) (step-index s)))))
    (labels ((walk (node)
               (let ((id (setf (gethash node ids) (incf n)))
                     (failure (cpl:node-failure node)))
                 (obj "id" id "kind" (string-downcase (symbol-name (cpl:node-kind node)))
                      "name" (cpl::name-string (cpl:node-name node))
                      "outcome" (string-downcase (symbol-name (cpl:node-outcome node)))
                      "designator" (cpl:node-designator node)
                      "duration" (cpl:node-duration node)
                      "failure" (and failure (format nil "~a: ~a" (getf failure :class) (getf failure :description)))
                      "first_step" (gethash node first-step)
                      "children" (mapcar #'walk (cpl:node-children node))))))
      (values (and root (walk root)) ids))))

(defun run-json (run &key embed-meshes)
  "RUN as JSON: its objects (descriptors), meshes (URLs, or the files inline with EMBED-MESHES),
steps (label, time, state, overlays, failed, task tree node) and task tree."
  (let* ((steps (sb-thread:with-mutex (*recorder-lock*) (copy-seq (run-steps run))))
         (descriptors (sb-thread:with-mutex (*recorder-lock*)
                        (loop for d being the hash-values of (run-descriptors run) collect d)))
         (counts (joint-counts descriptors)))
    (multiple-value-bind (tree ids) (tree-json (run-root run) steps)
      (obj "id" (run-id run) "label" (run-label run) "start_unix" (run-start-unix run)
           "objects" descriptors
           "meshes" (mesh-table (descriptor-meshes descriptors) :embed embed-meshes)
           "tree" tree
           "steps" (loop for s across steps
                         collect (obj "index" (step-index s) "label" (step-label s)
                                      "offset" (- (step-unix s) (run-start-unix run))
                                      "node" (and (step-node s) (gethash (step-node s) ids))
                                      "failed" (if (step-failed-p s) t :false)
                                      "state" (split-state (step-names s) (step-state s) counts)
                                      "overlays" (overlays-json (step-overlays s))))))))

;;; ---- the page ------------------------------------------------------------------------------------

(defun html-escape (text)
  (with-output-to-string (out)
    (loop for c across text
          do (case c (#\< (write-string "&lt;" out)) (#\> (write-string "&gt;" out))
                     (#\& (write-string "&amp;" out)) (#\" (write-string "&quot;" out))
                     (t (write-char c out))))))

(defun inline-safe (json)
  "JSON text safe inside a <script> element."
  (cl-ppcre:regex-replace-all "</" json "<\\/"))

(defun page-html (mode &key run inline-data (three-prefix "three/") inline-assets)
  "The viewer page for MODE :LIVE (served) or :REPLAY of the run numbered RUN (served) or of
INLINE-DATA (a run's JSON text, for a replay on disk). With INLINE-ASSETS the script and style
are written into the page."
  (check-type mode (member :live :replay))
  (flet ((asset (name) (uiop:read-file-string
                        (asdf:system-relative-pathname "cram-plans/replay"
                                                       (format nil "projection/viewer/~a" name)))))
    (with-output-to-string (s)
      (format s "<!DOCTYPE html>~%<html><head><meta charset=\"utf-8\"><title>cram-plans ~a</title>~%"
              (if (eq mode :live) "belief state" "replay"))
      (if inline-assets
          (format s "<style>~a</style>~%" (asset "viewer.css"))
          (format s "<link rel=\"stylesheet\" href=\"viewer.css\">~%"))
      (dolist (f '("three.min.js" "OrbitControls.js" "STLLoader.js" "OBJLoader.js" "ColladaLoader.js"
                   "ConvexHull.js" "ConvexGeometry.js"))
        (format s "<script src=\"~a~a\"></script>~%" three-prefix f))
      (if inline-assets
          (format s "<script>~a</script>~%" (asset "viewer.js"))
          (format s "<script src=\"viewer.js\"></script>~%"))
      (format s "</head><body>~%<div id=\"app\"></div>~%")
      (when inline-data
        (format s "<script type=\"application/json\" id=\"replay-data\">~a</script>~%" (inline-safe inline-data)))
      (format s "<script>CramViewer.start(~a);</script>~%</body></html>~%"
              (json-string (obj "mode" (string-downcase (symbol-name mode))
                                "run" run "inline" (if inline-data t :false)))))))

(defun replay-html (run)
  "A self-contained replay page of RUN (data, script and style inline; three.js from three/)."
  (page-html :replay :inline-data (json-string (run-json run :embed-meshes t)) :inline-assets t))

(defun write-replay (directory &key (run (last-run)))
  "Write the replay of RUN (default: the last recorded run) into DIRECTORY: replay.html, which
opens from disk without a server, replay.json, and three/ with the three.js files copied from
Debian's libjs-three. Returns the path of replay.html."
  (unless (typep run 'run)
    (error "WRITE-REPLAY: run ~s, expected a recorded run (none recorded yet?)" run))
  (unless (or (stringp directory) (pathnamep directory))
    (error "WRITE-REPLAY: directory ~s, expected a string or pathname" directory))
  (let* ((dir (uiop:ensure-directory-pathname directory))
         (json (json-string (run-json run :embed-meshes t)))
         (html (merge-pathnames "replay.html" dir)))
    (ensure-directories-exist (merge-pathnames "three/" dir))
    (dolist (entry *replay-three-files*)
      (let ((from (merge-pathnames (cdr entry) *replay-three-directory*)))
        (unless (probe-file from)
          (error "WRITE-REPLAY: ~a is missing: install Debian's libjs-three (make setup)" from))
        (uiop:copy-file from (merge-pathnames (format nil "three/~a" (car entry)) dir))))
    (with-open-file (out (merge-pathnames "replay.json" dir) :direction :output :if-exists :supersede
                                                             :external-format :utf-8)
      (write-string json out))
    (with-open-file (out html :direction :output :if-exists :supersede :external-format :utf-8)
      (write-string (page-html :replay :inline-data json :inline-assets t) out))
    html))


(defun html-unescape (text)
  "TEXT with the entities &lt; &gt; &quot; &#39; and &amp; replaced (for a page's dumped DOM)."
  (let ((s text))
    (loop for (from . to) in '(("&lt;" . "<") ("&gt;" . ">") ("&quot;" . "\"") ("&#39;" . "'") ("&amp;" . "&"))
          do (setf s (cl-ppcre:regex-replace-all from s to)))
    s))
