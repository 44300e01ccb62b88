;;;; Heat-map pictures of location costmaps.

(in-package :cram-location-costmap)

(defun heat-color (v)
  "RGB bytes for V in [0, 1]: dark blue through red to yellow and white."
  (let ((v (max 0d0 (min 1d0 v))))
    (flet ((b (x) (round (* 255 (max 0d0 (min 1d0 x))))))
      (values (b (* 3 v)) (b (- (* 3 v) 1)) (b (+ 0.35d0 (- (* 3 v) 2) (if (< v 0.34d0) (* 1.5d0 v) 0)))))))

(defun costmap-heat-map-image (costmap &key (scale 1) occupancy-grid (crop t))
  "COSTMAP's values as a heat-map image: (values rgb-bytes width height x-min y-min x-max y-max),
rows from north (+y) to south, SCALE pixels per cell, the last four values the map area the
image covers.  Cells of value 0 are dark grey, occupied cells of OCCUPANCY-GRID (when given) light
grey.  With CROP, only the part where the value is not 0 is drawn, with a margin of 1 m."
  (unless (typep costmap 'location-costmap)
    (error "COSTMAP-HEAT-MAP-IMAGE: expected a location costmap, got ~s." costmap))
  (unless (typep scale '(integer 1 16))
    (error "COSTMAP-HEAT-MAP-IMAGE: scale ~s, expected an integer from 1 to 16." scale))
  (when (and occupancy-grid (not (typep occupancy-grid 'occupancy-grid)))
    (error "COSTMAP-HEAT-MAP-IMAGE: occupancy grid ~s, expected an OCCUPANCY-GRID." occupancy-grid))
  (let* ((m (cost-grid costmap))
         (rows (costmap-rows costmap)) (cols (costmap-columns costmap))
         (maximum (loop for i below (array-total-size m) maximize (row-major-aref m i)))
         (r0 0) (r1 (1- rows)) (c0 0) (c1 (1- cols)))
    (declare (type (simple-array double-float (* *)) m))
    (when (and crop (> maximum 0))
      (let ((margin (ceiling 1 (resolution costmap)))
            (rmin rows) (rmax -1) (cmin cols) (cmax -1))
        (dotimes (r rows)
          (dotimes (c cols)
            (when (> (aref m r c) 0)
              (setf rmin (min rmin r) rmax (max rmax r) cmin (min cmin c) cmax (max cmax c)))))
        (setf r0 (max 0 (- rmin margin)) r1 (min (1- rows) (+ rmax margin))
              c0 (max 0 (- cmin margin)) c1 (min (1- cols) (+ cmax margin)))))
    (let* ((w (* scale (1+ (- c1 c0)))) (h (* scale (1+ (- r1 r0))))
           (rgb (make-array (* 3 w h) :element-type '(unsigned-byte 8)))
           (half (/ (resolution costmap) 2)))
      (loop for r from r0 to r1
            for y = (cell-center-y costmap r)
            do (loop for c from c0 to c1
                     for x = (cell-center-x costmap c)
                     for v = (aref m r c)
                     do (multiple-value-bind (red green blue)
                            (cond ((> v 0) (heat-color (/ v maximum)))
                                  ((and occupancy-grid (occupied-p occupancy-grid x y))
                                   (values 170 170 170))
                                  (t (values 40 40 40)))
                          (dotimes (i scale)
                            (dotimes (j scale)
                              (let* ((px (+ (* scale (- c c0)) j))
                                     (py (+ (* scale (- r1 r)) i))
                                     (k (* 3 (+ px (* py w)))))
                                (setf (aref rgb k) red (aref rgb (+ k 1)) green
                                      (aref rgb (+ k 2)) blue)))))))
      (values rgb w h
              (- (cell-center-x costmap c0) half) (- (cell-center-y costmap r0) half)
              (+ (cell-center-x costmap c1) half) (+ (cell-center-y costmap r1) half)))))

(defun costmap-heat-map-png (costmap path &key (scale 2) occupancy-grid (crop t))
  "Write COSTMAP's values as a heat-map PNG file PATH (north up: +y at the top, +x right), SCALE
pixels per cell.  Cells of value 0 are dark grey, occupied cells of OCCUPANCY-GRID (when given)
light grey.  With CROP, only the part where the value is not 0 is drawn, with a margin of 1 m.
Returns PATH."
  (unless (typep costmap 'location-costmap)
    (error "COSTMAP-HEAT-MAP-PNG: expected a location costmap, got ~s." costmap))
  (unless (or (stringp path) (pathnamep path))
    (error "COSTMAP-HEAT-MAP-PNG: the path is ~s, expected a string or pathname." path))
  (unless (typep scale '(integer 1 16))
    (error "COSTMAP-HEAT-MAP-PNG: scale ~s, expected an integer from 1 to 16." scale))
  (when (and occupancy-grid (not (typep occupancy-grid 'occupancy-grid)))
    (error "COSTMAP-HEAT-MAP-PNG: occupancy grid ~s, expected an OCCUPANCY-GRID." occupancy-grid))
  (multiple-value-bind (rgb w h)
      (costmap-heat-map-image costmap :scale scale :occupancy-grid occupancy-grid :crop crop)
    (ensure-directories-exist path)
    (cram-native:write-png (namestring path) rgb w h)
    path))

(setf (documentation 'occupancy-bits 'function)
      "The bit array of an OCCUPANCY-GRID: 1 for an occupied cell, row = y index.")
