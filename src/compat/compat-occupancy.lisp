;;;; CRAM-OCCUPANCY-GRID-COSTMAP: the occupancy map the robot navigates by, read from the map
;;;; server's files (a YAML file and its PGM image, as launch/world.launch publishes on /map).

(in-package :cram-occupancy-grid-costmap)

(defvar *occupancy-map-file* nil
  "The map YAML file INIT-OCCUPANCY-GRID-COSTMAP reads; NIL: resources/maps/kitchen.yaml.")

(defparameter *default-map-file*
  (merge-pathnames "../../resources/maps/kitchen.yaml"
                   (make-pathname :name nil :type nil :defaults #.(or *compile-file-truename* *load-truename*)))
  "resources/maps/kitchen.yaml of this checkout: the map launch/world.launch publishes.")

(defvar *occupancy-grid* nil "The grid INIT-OCCUPANCY-GRID-COSTMAP read.")

(defstruct (grid (:conc-name occupancy-grid-))
  width height resolution origin (cells nil :type (or null simple-bit-vector)))

(defun yaml-value (lines key)
  (let ((line (find-if (lambda (l) (uiop:string-prefix-p (format nil "~a:" key) (string-trim " " l))) lines)))
    (unless line (error "Occupancy map: the YAML file has no ~a: entry." key))
    (string-trim " " (subseq line (1+ (position #\: line))))))

(defun read-pgm (path)
  "(values width height maxval pixels) of the binary (P5) PGM file PATH."
  (with-open-file (in path :element-type '(unsigned-byte 8))
    (labels ((token ()
               (let ((chars '()) (c (read-byte in)))
                 (loop while (or (member c '(32 9 10 13)) (= c 35))
                       do (if (= c 35)
                              (loop until (= (read-byte in) 10) finally (setf c (read-byte in)))
                              (setf c (read-byte in))))
                 (loop until (member c '(32 9 10 13))
                       do (push (code-char c) chars) (setf c (read-byte in)))
                 (coerce (nreverse chars) 'string))))
      (let ((magic (token)))
        (unless (string= magic "P5")
          (error "Occupancy map ~a: ~s is not a binary PGM (P5) header." path magic)))
      (let* ((w (parse-integer (token))) (h (parse-integer (token))) (max (parse-integer (token)))
             (pixels (make-array (* w h) :element-type '(unsigned-byte 8))))
        (read-sequence pixels in)
        (values w h max pixels)))))

(defun init-occupancy-grid-costmap (&optional (file *occupancy-map-file*))
  "Read the occupancy map FILE (a map_server YAML file; default resources/maps/kitchen.yaml,
the map launch/world.launch publishes) into the grid OCCUPANCY-GRID returns."
  (let* ((yaml (or file *default-map-file*))
         (lines (uiop:read-file-lines yaml))
         (image (merge-pathnames (string-trim "\"'" (yaml-value lines "image")) yaml))
         (resolution (let ((*read-default-float-format* 'double-float))
                       (read-from-string (yaml-value lines "resolution"))))
         (origin (let ((s (yaml-value lines "origin")))
                   (let ((*read-default-float-format* 'double-float))
                     (read-from-string (format nil "(~a)" (substitute #\Space #\, (string-trim "[]" s)))))))
         (negate (string= "1" (yaml-value lines "negate")))
         (occupied (read-from-string (yaml-value lines "occupied_thresh"))))
    (multiple-value-bind (w h max pixels) (read-pgm image)
      (let ((cells (make-array (* w h) :element-type 'bit)))
        ;; map_server: p = (255 - x) / 255 (or x / 255 negated); image row 0 is the top (max y)
        (dotimes (row h)
          (dotimes (col w)
            (let* ((x (aref pixels (+ col (* row w))))
                   (p (if negate (/ x max) (/ (- max x) max))))
              (setf (sbit cells (+ col (* (- h 1 row) w))) (if (> p occupied) 1 0)))))
        (setf *occupancy-grid*
              (make-grid :width w :height h :resolution resolution
                         :origin (list (first origin) (second origin)) :cells cells))))))

(defun occupancy-grid ()
  "The occupancy grid read by INIT-OCCUPANCY-GRID-COSTMAP, or NIL."
  *occupancy-grid*)

(defun occupied-p (x y &optional (grid *occupancy-grid*))
  "True when the map point (X Y) is occupied (or off the map) in GRID."
  (unless grid (error "OCCUPIED-P: no occupancy grid; call (init-occupancy-grid-costmap) first."))
  (let ((col (floor (- x (first (occupancy-grid-origin grid))) (occupancy-grid-resolution grid)))
        (row (floor (- y (second (occupancy-grid-origin grid))) (occupancy-grid-resolution grid))))
    (or (not (< -1 col (occupancy-grid-width grid)))
        (not (< -1 row (occupancy-grid-height grid)))
        (= 1 (sbit (occupancy-grid-cells grid) (+ col (* row (occupancy-grid-width grid))))))))
