// A strip chart for the trainer (Qt's painter, no plotting library): series of (time, value) over
// the last `window_s` seconds, with an optional horizontal limit line (a budget). The axis spans 0
// and every value shown, negative ones included.
#pragma once

#include <QColor>
#include <QPainter>
#include <QString>
#include <QWidget>

#include <algorithm>
#include <cmath>
#include <deque>
#include <utility>
#include <vector>

namespace fetouch::app::trainer {

class TracePlot : public QWidget {
 public:
  TracePlot(const QString& title, const QString& unit, double window_s, QWidget* parent = nullptr)
      : QWidget(parent), title_(title), unit_(unit), window_s_(window_s) {
    setMinimumHeight(110);
  }
  void set_series(int count) {
    series_.resize(static_cast<std::size_t>(count));
  }
  void add(int series, double time_s, double value) {
    if (series < 0 || series >= static_cast<int>(series_.size()) || !std::isfinite(value)) return;
    auto& s = series_[static_cast<std::size_t>(series)];
    s.emplace_back(time_s, value);
    while (!s.empty() && s.front().first < time_s - window_s_) s.pop_front();
    now_ = std::max(now_, time_s);
  }
  void set_limit(double value, const QString& label) { limit_ = value, limit_label_ = label; }
  void clear() {
    for (auto& s : series_) s.clear();
    now_ = 0;
  }

 protected:
  void paintEvent(QPaintEvent*) override {
    QPainter p(this);
    p.fillRect(rect(), QColor(24, 26, 32));
    const QRect area = rect().adjusted(44, 18, -8, -16);
    double top = limit_ > 0 ? 1.2 * limit_ : 0, bottom = 0;
    for (const auto& s : series_)
      for (const auto& v : s) top = std::max(top, v.second), bottom = std::min(bottom, v.second);
    top = top > 0 ? top * 1.1 : (bottom < 0 ? 0 : 1);
    bottom *= 1.1;
    p.setPen(QColor(200, 200, 200));
    p.drawText(rect().adjusted(4, 2, 0, 0), Qt::AlignLeft | Qt::AlignTop, title_);
    p.drawText(QRect(0, area.top() - 6, 42, 14), Qt::AlignRight, QString::number(top, 'g', 3));
    p.drawText(QRect(0, area.bottom() - 8, 42, 14), Qt::AlignRight,
               (bottom < 0 ? QString::number(bottom, 'g', 3) : QString("0")) + " " + unit_);
    p.setPen(QColor(70, 70, 80));
    p.drawRect(area);
    const auto x_of = [&](double t) { return area.right() - (now_ - t) / window_s_ * area.width(); };
    const auto y_of = [&](double v) { return area.bottom() - (v - bottom) / (top - bottom) * area.height(); };
    if (bottom < 0) {  // the zero line
      p.setPen(QPen(QColor(110, 110, 120), 1, Qt::DotLine));
      p.drawLine(QPointF(area.left(), y_of(0)), QPointF(area.right(), y_of(0)));
    }
    if (limit_ > 0 || (bottom < 0 && limit_ == 0 && !limit_label_.isEmpty())) {
      p.setPen(QPen(QColor(230, 80, 80), 1, Qt::DashLine));
      p.drawLine(QPointF(area.left(), y_of(limit_)), QPointF(area.right(), y_of(limit_)));
      p.drawText(QPointF(area.left() + 4, y_of(limit_) - 3), limit_label_);
    }
    static const QColor kColours[] = {QColor(90, 200, 120), QColor(90, 160, 250), QColor(240, 190, 60), QColor(220, 110, 220)};
    for (std::size_t i = 0; i < series_.size(); ++i) {
      p.setPen(QPen(kColours[i % 4], 1.5));
      QPointF last;
      bool first = true;
      for (const auto& [t, v] : series_[i]) {
        const QPointF point(x_of(t), y_of(v));
        if (!first) p.drawLine(last, point);
        last = point, first = false;
      }
    }
  }

 private:
  QString title_, unit_, limit_label_;
  double window_s_, limit_ = 0, now_ = 0;
  std::vector<std::deque<std::pair<double, double>>> series_;
};

}  // namespace fetouch::app::trainer
